//! Issue 30 on a mesh like a production creature's: the test head, open at
//! its eye sockets and neck, with eyeballs, a horn and ears as separate
//! closed shells that pass through it, and very uneven triangles.
//! - the stamp keeps its spacing across the shells and grows no root where
//!   the skin is buried in the body;
//! - settle leaves no hair point inside the body, by the generalized winding
//!   number of the whole mesh (checked triangle by triangle on a sample),
//!   and resolves every strand;
//! - on it and on the test creature, 10K and 100K roots leave no hole wider than
//!   1.1 r_hex, and their 50% and 25% rank prefixes are as even as asked.

use glam::Vec3;
use pelage::*;
use pelage_core::surface::body::Body;
use pelage_core::Arena;
use pelage_tests::creature::default_creature;
use pelage_tests::head::head_with_parts;
use pelage_tests::measure::{
    groomed, mesh_desc, mesh_view, on_threads, stamp_roots, stamp_vec, ExpandCall,
};
use pelage_tests::quality::{empty_space, neighbours, prefix, winding_number, Skin};

const CVS: usize = 12;

#[test]
fn the_stamp_keeps_its_spacing_across_shells_and_skips_buried_skin() {
    let (m, parts) = head_with_parts();
    let mesh = mesh_view(&m);
    let shells = parts.shells();
    let mut memory = vec![0u8; Body::required_bytes(&mesh).unwrap()];
    let body = Body::new(&mesh, &mut Arena::new(&mut memory)).unwrap();
    let skin = Skin::new(mesh, &shells, |_| true);
    for target in [30_000u32, 100_000] {
        let (roots, report) = stamp_vec(
            mesh,
            &pelage_core::stamp::StampParams {
                target_count: target,
                seed: 3,
                ..Default::default()
            },
        );
        assert_eq!(roots.len(), target as usize, "{report:?}");
        // 3D distances run a hair under the radius on curved faces (the
        // tile spaces points on the unfolded surface)
        let n = neighbours(&skin, &roots, report.radius * 0.999);
        assert_eq!((n.close_pairs, n.close_across_shells), (0, 0), "{target}");
        let buried = roots
            .iter()
            .filter(|r| {
                let f = r.face as usize;
                let lift = mesh.face_normal(f) * (1e-3 * report.radius);
                body.capped_winding(mesh.point(f, r.u, r.v) + lift) >= 1
            })
            .count();
        // a face no other shell comes near is decided at its centroid: a
        // root a hair from a concave crease may read otherwise
        assert!(
            buried * 10_000 <= roots.len(),
            "{target}: {buried} roots on buried skin"
        );
        // the horn's base and the eyeballs' backs lie inside the head
        let on = |range: &std::ops::Range<usize>| {
            roots
                .iter()
                .filter(|r| range.contains(&(r.face as usize)))
                .count()
        };
        assert!(on(&parts.horn) > 0 && on(&parts.head) > 0);
    }
}

/// Issue 30's targets at 100K roots, on `mesh` with `shells`: the skin's
/// empty space (buried skin left out), the spacing, and the 50% and 25%
/// rank prefixes, in units of r_hex.
fn meets_the_quality_targets(m: &pelage_tests::creature::CreatureMesh, shells: &[u32]) {
    with_unburied_skin(m, shells, |mesh, skin| {
        // 10K takes its ranks from sample elimination, 100K from the tile
        for count in [10_000, 100_000] {
            let roots = stamp_roots(mesh, count, 1);
            let e = empty_space(skin, &roots, 32, 7);
            assert!(e.p999 <= 0.85 && e.max <= 1.1, "{count}: {e:?}");
            let n = neighbours(skin, &roots, 0.0);
            assert!(n.min >= 0.70 && n.mean >= 0.78, "{count}: {n:?}");
            for fraction in [0.5, 0.25] {
                let p = prefix(skin, &roots, fraction);
                assert!(p.cv <= 0.12 && p.min >= 0.5, "{count}, {fraction}: {p:?}");
            }
        }
    });
}

/// Runs `f` with `m`'s mesh and its skin with `shells`, buried skin left
/// out.
fn with_unburied_skin<R>(
    m: &pelage_tests::creature::CreatureMesh,
    shells: &[u32],
    f: impl FnOnce(pelage_core::Mesh, &Skin) -> R,
) -> R {
    let mesh = mesh_view(m);
    let mut memory = vec![0u8; Body::required_bytes(&mesh).unwrap()];
    let body = Body::new(&mesh, &mut Arena::new(&mut memory)).unwrap();
    f(mesh, &Skin::unburied(mesh, shells, |_| true, &body))
}

#[test]
fn the_stamp_leaves_no_wide_hole_and_its_prefixes_are_even() {
    let (head, parts) = head_with_parts();
    meets_the_quality_targets(&head, &parts.shells());
    let creature = default_creature();
    meets_the_quality_targets(&creature, &vec![0; creature.triangle_count()]);
}

/// At 1M roots the head's widest hole was on its skin beside an eyeball
/// that passes through it, where the buried points were dropped and
/// nothing refilled the skin beside them (1.16 r_hex before the fill
/// threw darts on the faces the edge of buried skin crosses).
#[test]
fn a_million_roots_leave_no_wide_hole_beside_buried_skin() {
    let (head, parts) = head_with_parts();
    with_unburied_skin(&head, &parts.shells(), |mesh, skin| {
        let roots = stamp_roots(mesh, 1_000_000, 1);
        let e = empty_space(skin, &roots, 8, 7);
        assert!(e.p999 <= 0.85 && e.max <= 1.1, "{e:?}");
        // the darts there are spaced from every point, not only those near
        // a cut edge
        let n = neighbours(skin, &roots, 0.0);
        assert!(n.min >= 0.70 && n.mean >= 0.78, "{n:?}");
    });
}

#[test]
fn settle_leaves_no_point_inside_an_open_head_with_shells() {
    let (m, _) = head_with_parts();
    let mesh = mesh_view(&m);
    let mut maps = pelage_groom_maps_defaults();
    maps.clump.constant = 0.3;
    maps.bend.constant = 0.2;
    let mut g = groomed(&m, (3_000, CVS, 0.12), 40_000, &maps, 2);
    let params = PelageExpandParams {
        run: on_threads(2),
        ..pelage_expand_params_defaults()
    };
    let settle = g.settle(&m, &params);
    assert!(settle.lifted > 0, "{settle:?}");
    assert_eq!(settle.unresolved, 0, "{settle:?}");

    let mut per = 0usize;
    assert_eq!(pelage_expand_size(&params, &mut per), PelageStatus::Ok);
    let mut out = vec![[0.0f32; 4]; g.strands.len() * per];
    let call = ExpandCall {
        mesh: &mesh_desc(&m),
        guides: &g.guides(),
        strands: &g.strands,
        bindings: &g.bindings,
        grooms: &g.grooms,
        params: &params,
    };
    assert_eq!(call.run(&mut out, None), PelageStatus::Ok);
    let mut memory = vec![0u8; Body::required_bytes(&mesh).unwrap()];
    let body = Body::new(&mesh, &mut Arena::new(&mut memory)).unwrap();
    // every point after the root by the body, and a sample of them
    // triangle by triangle
    // (the root is repeated at the start of a Catmull-Rom curve)
    let points: Vec<Vec3> = out
        .chunks(per)
        .flat_map(|s| {
            let root = Vec3::new(s[0][0], s[0][1], s[0][2]);
            s.iter()
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .filter(move |p| p.distance(root) > 1e-6)
        })
        .collect();
    let inside: Vec<&Vec3> = points.iter().filter(|&&p| body.contains(p)).collect();
    assert!(
        inside.is_empty(),
        "{} points inside, e.g. {:?}",
        inside.len(),
        inside.first()
    );
    for p in points.iter().step_by(points.len() / 1500) {
        let w = winding_number(&mesh, *p);
        assert!(w <= 0.5, "{p}: winding number {w}");
    }
}
