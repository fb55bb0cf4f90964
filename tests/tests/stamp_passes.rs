//! The edge-loss model behind the first stamping radius: on dense stamps
//! (several roots per triangle) it predicts how many roots the edge pass
//! removes, so the first pass lands close to the target and the measured
//! count corrects the rest in at most one more pass.

use pelage_core::stamp::{self, Candidate, Scratch, StampParams, Stamper};
use pelage_core::Arena;
use pelage_tests::creature::{creature, default_creature};
use pelage_tests::measure::{mesh_view, stamp_vec};

/// Roots the first pass keeps.
fn first_pass(params: &StampParams, mesh: pelage_core::Mesh) -> usize {
    let mut buf = vec![0u8; stamp::required_bytes(&mesh, params).unwrap()];
    let mut arena = Arena::new(&mut buf);
    let stamper = Stamper::new(mesh, params, &mut arena).unwrap().unwrap();
    let faces = 0..mesh.triangle_count();
    let bound = stamper.candidate_bound(faces.clone());
    let mut scratch = Scratch::new(&mut arena, bound).unwrap();
    let cands = arena.alloc::<Candidate>(bound).unwrap();
    let n = stamper.stamp_faces(faces, cands).unwrap();
    stamper.prune(&mut cands[..n], &mut scratch).unwrap()
}

#[test]
fn the_first_pass_lands_near_the_target_on_dense_stamps() {
    let meshes = [default_creature(), creature(90, 90), creature(400, 400)];
    for (m, target) in meshes.iter().zip([1_000_000u32, 1_000_000, 3_000_000]) {
        for seed in [1, 2] {
            let params = StampParams {
                target_count: target,
                seed,
                ..StampParams::default()
            };
            let mesh = mesh_view(m);
            let error = first_pass(&params, mesh) as f32 / target as f32 - 1.0;
            // the edge pass removes 8% to 28% of these stamps
            assert!(
                error.abs() < 0.025,
                "{} triangles: {error}",
                m.triangle_count()
            );
            let (roots, report) = stamp_vec(mesh, &params);
            assert_eq!(roots.len(), target as usize);
            assert!(report.passes <= 2, "{report:?}");
        }
    }
}

/// Sparse stamps, where the fill wins back more than the edge pass removed
/// (more cut edge per root): the first radius counts with it, so they too
/// land in the count band in one pass, on the creature and on the head;
/// but for the head at 3,000 roots, whose horn and ears meet it in concave
/// creases: since roots facing each other across one keep their distance
/// (0.12), those lose more than the model of cut edges predicts at that
/// sparsity, and a second pass lands it.
#[test]
fn sparse_stamps_land_in_one_pass() {
    let meshes = [default_creature(), pelage_tests::head::head()];
    for (k, m) in meshes.iter().enumerate() {
        for target in [3_000u32, 10_000, 30_000] {
            let params = StampParams {
                target_count: target,
                seed: 1,
                ..StampParams::default()
            };
            let (roots, report) = stamp_vec(mesh_view(m), &params);
            assert_eq!(roots.len(), target as usize);
            let passes = if k == 1 && target == 3_000 { 2 } else { 1 };
            assert!(report.passes <= passes, "{target}: {report:?}");
        }
    }
}
