//! The guide cache decoder on damaged caches: never a panic; on failure the
//! frame keeps its guides, on success every decoded point is finite.
#![no_main]

mod scene;

use libfuzzer_sys::fuzz_target;
use pelage_core::cache::guide_cache::{self, GuideCache, Mode};
use std::sync::OnceLock;

const GROOM_ID: u32 = 7;

struct Fixture {
    scene: scene::Scene,
    /// Valid caches: quantized 1 and 2 samples, exact 1 sample.
    caches: Vec<Vec<u8>>,
}

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let scene = scene::Scene::new();
        let groom = scene.groom();
        let mut caches = vec![];
        for (mode, samples) in [(Mode::Quantized, 1), (Mode::Quantized, 2), (Mode::Exact, 1)] {
            let bytes = scene::with_frame(0.7, &scene.guide_roots, |a| {
                scene::with_frame(1.3, &scene.guide_roots, |b| {
                    let s = [a, b];
                    let s = &s[..samples];
                    let most =
                        guide_cache::max_encoded_bytes(scene::GUIDES, scene::POINTS, samples, mode);
                    let mut out = vec![0u8; most.unwrap()];
                    let n = guide_cache::encode(&groom, GROOM_ID, s, mode, &mut out).unwrap();
                    out.truncate(n);
                    out
                })
            });
            caches.push(bytes);
        }
        Fixture { scene, caches }
    })
}

fuzz_target!(|data: &[u8]| {
    let Some((&flags, edits)) = data.split_first() else {
        return;
    };
    let f = fixture();
    let bytes = if flags & 1 == 1 {
        edits.to_vec()
    } else {
        let mut b = f.caches[(flags as usize >> 2) % f.caches.len()].clone();
        scene::damage(&mut b, edits, 32 + 8 * 6 - 8, flags & 2 == 2);
        b
    };
    let Ok(cache) = GuideCache::parse(&bytes) else {
        return;
    };
    let groom = f.scene.groom();
    let sample = (flags as usize >> 4) % 3;
    scene::with_target(1.0, |frame| {
        let before: Vec<_> = (0..scene::GUIDES * scene::POINTS)
            .map(|k| frame.world_point(k / scene::POINTS, k % scene::POINTS))
            .collect();
        let mut scratch = vec![0; cache.scratch_words()];
        let ok = cache
            .decode(&groom, GROOM_ID, sample, frame, &mut scratch)
            .is_ok();
        for k in 0..scene::GUIDES * scene::POINTS {
            let (p, l) = (
                frame.world_point(k / scene::POINTS, k % scene::POINTS),
                frame.local_point(k / scene::POINTS, k % scene::POINTS),
            );
            if ok {
                assert!(p.is_finite() && l.is_finite(), "non-finite point decoded");
            } else {
                assert!(p == before[k], "a failed decode wrote the frame");
            }
        }
    });
});
