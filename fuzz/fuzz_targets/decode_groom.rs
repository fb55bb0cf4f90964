//! The groom file decoder on damaged files: never a panic, and on success
//! only finite values that pass the groom's own checks.
#![no_main]

mod scene;

use libfuzzer_sys::fuzz_target;
use pelage_core::cache::groom_file::{self, Groom, GroomBuffers};
use pelage_core::interp::bind::StrandBinding;
use pelage_core::interp::groom::StrandGroom;
use pelage_core::interp::patch::Patch;
use pelage_core::interp::strands::Strands;
use pelage_core::Root;
use std::sync::OnceLock;

fn valid() -> &'static Vec<u8> {
    static FILE: OnceLock<Vec<u8>> = OnceLock::new();
    FILE.get_or_init(|| {
        let s = scene::Scene::new();
        let groom = s.groom();
        let mut out = vec![0u8; groom.encoded_bytes().unwrap()];
        groom_file::encode(&groom, &mut out).unwrap();
        out
    })
}

fuzz_target!(|data: &[u8]| {
    let Some((&flags, edits)) = data.split_first() else {
        return;
    };
    // bit 0: the input itself is the file; else a valid file, damaged
    let bytes = if flags & 1 == 1 {
        edits.to_vec()
    } else {
        let mut b = valid().clone();
        scene::damage(&mut b, edits, 32 + 8 * 4 - 8, flags & 2 == 2);
        b
    };
    let Ok(c) = groom_file::counts(&bytes) else {
        return;
    };
    // counts are checked against the payload, so they are small here
    let mut guide_roots = vec![Root::default(); c.guides];
    let mut guide_points = vec![[0.0f32; 3]; c.guides * c.points];
    let mut roots = vec![Root::default(); c.strands];
    let mut bindings = vec![StrandBinding::default(); c.strands];
    let mut grooms = vec![StrandGroom::default(); c.strands];
    let mut patches = vec![Patch::default(); c.patches];
    let out = GroomBuffers {
        guide_roots: &mut guide_roots,
        guide_points: &mut guide_points,
        roots: &mut roots,
        bindings: &mut bindings,
        grooms: &mut grooms,
        patches: &mut patches,
    };
    if groom_file::decode(&bytes, out).is_ok() {
        let groom = Groom {
            guide_roots: &guide_roots,
            guide_points: &guide_points,
            points: c.points,
            strands: Strands {
                roots: &roots,
                bindings: &bindings,
                grooms: &grooms,
            },
            patches: &patches,
        };
        groom.check().expect("a decoded groom passes its checks");
    }
});
