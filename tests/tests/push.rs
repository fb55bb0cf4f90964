//! Render hairs in user regions (paper 3.3), end to end through the C API
//! on the animated creature: interpolated hairs enter the capsules and the
//! body although the simulated guides are clear; the hairs a mask over the
//! body selects are pushed out at expansion, every frame, and no point of
//! theirs is left inside (a hair no rotation frees is cut where it enters;
//! hairs rooted inside a capsule are left out: nothing about the root frees
//! them). The others are untouched, bit for bit.

use glam::Vec3;
use pelage::*;
use pelage_core::surface::body::Body;
use pelage_core::Arena;
use pelage_tests::animated::{capsules, colliders, pose, segment_distance};
use pelage_tests::creature::default_creature;
use pelage_tests::measure::{
    curves_desc, frame, groomed, guides_desc, mesh_desc, mesh_view, on_threads, strands_desc,
};
use std::ptr::null_mut;

const JOINTS: usize = 12;
const GUIDES: u32 = 1_500;
const LENGTH: f32 = 0.08;
const HAIRS: u32 = 30_000;
const FRAMES: u32 = 24;

fn ok(s: PelageStatus, what: &str) {
    assert_eq!(s, PelageStatus::Ok, "{what}");
}

#[test]
fn masked_hairs_are_pushed_out_of_the_colliders_every_frame() {
    let rest = default_creature();
    let fur = groomed(
        &rest,
        (GUIDES, JOINTS, LENGTH),
        HAIRS,
        &pelage_groom_maps_defaults(),
        2,
    );
    let n = fur.strands.len();

    // the mask: a per-vertex map, 1 within 0.15 of a capsule at rest
    let rest_caps = capsules(&rest, &fur.guide_roots, 0);
    let near: Vec<f32> = rest
        .positions
        .iter()
        .map(|&p| {
            let p = Vec3::from(p);
            let close = rest_caps
                .iter()
                .any(|c| segment_distance(p, c.a.into(), c.b.into()) < 0.15);
            close as u32 as f32
        })
        .collect();
    let map = PelageMap {
        kind: PelageMapKind::PerVertex as u32,
        constant: 0.0,
        data: near.as_ptr().cast(),
        width: 0,
        height: 0,
        stride: 4,
    };
    let mut mask = vec![0u8; n];
    ok(
        pelage_map_mask(
            &mesh_desc(&rest),
            &map,
            fur.strands.as_ptr().cast::<PelageRoot>(),
            n,
            0.5,
            mask.as_mut_ptr(),
        ),
        "pelage_map_mask",
    );
    let masked = mask.iter().filter(|&&m| m != 0).count();
    assert!(
        (n / 50..n / 4).contains(&masked),
        "{masked} of {n} hairs masked"
    );

    let mut groom = null_mut();
    ok(
        pelage_groom_new(
            &strands_desc(&fur.strands, &fur.bindings, &fur.grooms),
            &mut groom,
        ),
        "pelage_groom_new",
    );
    let sim =
        pelage_tests::animated::ShotSim::new(&rest, &fur.guide_roots, &fur.guide_points, JOINTS);
    let params = |threads| PelageExpandParams {
        points_per_strand: JOINTS as u32,
        end_points: PelageEndPoints::Raw as u32,
        run: on_threads(threads),
        ..pelage_expand_params_defaults()
    };
    let edits = PelageStrandEdits {
        lengths: std::ptr::null(),
        push_mask: mask.as_ptr(),
    };
    let (mut inside_before, mut inside_after, mut rooted_inside) = (0usize, 0usize, 0usize);
    let mut clear_kept = 0usize;
    for f in 0..FRAMES {
        let body = pose(&rest, f);
        let caps = capsules(&rest, &fur.guide_roots, f);
        let col = colliders(&caps, true);
        let posed = sim.step(&body, &col);
        let handle = frame(
            &mesh_desc(&body),
            &guides_desc(&fur.guide_roots, &posed),
            JOINTS as u32,
            2,
        )
        .unwrap();
        ok(
            pelage_frame_set_colliders(handle.0, &col, on_threads(2)),
            "pelage_frame_set_colliders",
        );
        let expand = |edits: Option<&PelageStrandEdits>, threads| {
            let mut out = vec![[0.0f32; 4]; n * JOINTS];
            let e = edits.map_or(std::ptr::null(), |e| e as *const _);
            ok(
                pelage_groom_expand_edited(
                    groom,
                    handle.0,
                    0,
                    n,
                    e,
                    &params(threads),
                    &curves_desc(&mut out, None),
                ),
                "pelage_groom_expand_edited",
            );
            out
        };
        let plain = expand(None, 2);
        let pushed = expand(Some(&edits), 2);
        assert!(
            pushed == expand(Some(&edits), 1),
            "frame {f}: any thread count"
        );

        let view = mesh_view(&body);
        let mut memory = vec![0u8; Body::required_bytes(&view).unwrap()];
        let solid = Body::new(&view, &mut Arena::new(&mut memory)).unwrap();
        let inside = |p: Vec3| {
            caps.iter()
                .any(|c| segment_distance(p, c.a.into(), c.b.into()) < c.radius)
                || solid.contains(p)
        };
        let count = |curves: &[[f32; 4]], i: usize| {
            curves[i * JOINTS + 1..(i + 1) * JOINTS]
                .iter()
                .filter(|q| inside(Vec3::new(q[0], q[1], q[2])))
                .count()
        };
        for i in 0..n {
            let (a, b) = (
                &plain[i * JOINTS..(i + 1) * JOINTS],
                &pushed[i * JOINTS..(i + 1) * JOINTS],
            );
            if mask[i] == 0 {
                assert!(a == b, "frame {f}: hair {i} is not masked");
            } else {
                // a root inside a capsule (they touch the skin) has no way
                // out by a rotation about it
                let root = Vec3::from_slice(&b[0]);
                if caps
                    .iter()
                    .any(|c| segment_distance(root, c.a.into(), c.b.into()) < c.radius)
                {
                    rooted_inside += 1;
                    continue;
                }
                let before = count(&plain, i);
                inside_before += before;
                inside_after += count(&pushed, i);
                assert_eq!(a[0], b[0], "frame {f}: hair {i} keeps its root");
                if before == 0 {
                    // a masked hair already clear comes back as it was
                    assert!(a == b, "frame {f}: clear hair {i} was moved");
                    clear_kept += 1;
                }
            }
        }
    }
    println!(
        "{masked} of {n} hairs masked; points inside a capsule or the body over {FRAMES} frames: \
         {inside_before} expanded, {inside_after} pushed out ({rooted_inside} hair-frames rooted \
         inside a capsule left out; {clear_kept} masked hair-frames clear and unchanged)"
    );
    assert!(inside_before > 0, "interpolation leaves hairs inside");
    assert!(clear_kept > 0, "no masked hair was clear: nothing checked");
    assert_eq!(inside_after, 0, "no masked hair point is left inside");
    pelage_groom_free(groom);
}
