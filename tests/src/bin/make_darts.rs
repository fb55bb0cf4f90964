//! `make_darts <out_dir>`: write the dart-throwing reference roots the
//! Embree coverage harness compares pelage's stamp with (issue 30: "a plain
//! dart-throwing Poisson set of the same count"): for the creature and the
//! head, at constant density (the skin buried inside another shell left
//! bald, pelage's rule), 30,000 and 100,000 roots each, as
//! `darts_<mesh>_<count>.bin` in `out_dir`: the `PelageRoot` records
//! (face u32, u f32, v f32, id u32, rank u32; little-endian, 20 bytes
//! each) of `pelage_tests::quality::dart_throwing`, seed 1. The meshes are
//! those `make_creature` and `make_head` write, face for face.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use pelage_core::surface::body::Body;
use pelage_core::Arena;
use pelage_tests::creature::{default_creature, CreatureMesh};
use pelage_tests::head::head_with_parts;
use pelage_tests::measure::mesh_view;
use pelage_tests::quality::{dart_throwing, Skin};

/// The counts the harness measures.
const COUNTS: [usize; 2] = [30_000, 100_000];

fn main() -> ExitCode {
    let mut args = std::env::args_os().skip(1);
    let (Some(out), None) = (args.next(), args.next()) else {
        eprintln!("usage: make_darts <out_dir>");
        return ExitCode::from(2);
    };
    let out = PathBuf::from(out);
    match run(&out) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("make_darts: {}: {e}", out.display());
            ExitCode::FAILURE
        }
    }
}

fn run(out: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(out)?;
    let creature = default_creature();
    write(
        out,
        "creature",
        &creature,
        &vec![0; creature.triangle_count()],
    )?;
    let (head, parts) = head_with_parts();
    write(out, "head", &head, &parts.shells())
}

fn write(out: &Path, name: &str, m: &CreatureMesh, shells: &[u32]) -> std::io::Result<()> {
    let mesh = mesh_view(m);
    let mut body_memory = vec![0u8; Body::required_bytes(&mesh).expect("a valid test mesh")];
    let body = Body::new(&mesh, &mut Arena::new(&mut body_memory)).expect("a valid test mesh");
    let skin = Skin::unburied(mesh, shells, |_| true, &body);
    for n in COUNTS {
        let t = Instant::now();
        let darts = dart_throwing(&skin, n, 1);
        let path = out.join(format!("darts_{name}_{n}.bin"));
        let bytes: Vec<u8> = darts
            .roots
            .iter()
            .flat_map(|r| {
                [r.face, r.u.to_bits(), r.v.to_bits(), r.id, r.rank]
                    .into_iter()
                    .flat_map(u32::to_le_bytes)
            })
            .collect();
        std::fs::write(&path, bytes)?;
        println!(
            "{}: {} roots, radius {:.5}, in {:.1} s",
            path.display(),
            darts.roots.len(),
            darts.radius,
            t.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
