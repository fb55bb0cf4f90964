use super::near::Near;
use super::sizing::HEX_PACKING;
use super::tile::LEVEL_STEPS;
use super::*;
use crate::testmesh::{graded_plane, seamed_sphere, sphere};
use crate::Strided;

pub(crate) fn run(mesh: Mesh, params: &StampParams) -> (Vec<Root>, StampReport) {
    let mut buf = vec![0u8; required_bytes(&mesh, params).unwrap()];
    let mut out = vec![Root::default(); max_roots(&mesh, params).unwrap()];
    let mut arena = Arena::new(&mut buf);
    let (n, report) = stamp(mesh, params, &mut arena, &mut out).unwrap();
    out.truncate(n);
    // in face order, as documented (the fill's darts included)
    assert!(out.windows(2).all(|w| w[0].face <= w[1].face));
    // in the triangle, in f32 as a host checks it
    for r in &out {
        assert!(r.u >= 0.0 && r.v >= 0.0 && r.u + r.v <= 1.0, "{r:?}");
    }
    (out, report)
}

/// Minimum 3D distance between same-side roots (normals not opposed).
fn min_spacing(mesh: &Mesh, roots: &[Root]) -> f32 {
    let pts: Vec<(Vec3, Vec3)> = roots
        .iter()
        .map(|r| {
            (
                mesh.point(r.face as usize, r.u, r.v),
                mesh.face_normal(r.face as usize),
            )
        })
        .collect();
    let mut best = f32::INFINITY;
    for (i, a) in pts.iter().enumerate() {
        for b in &pts[i + 1..] {
            if a.1.dot(b.1) > 0.0 {
                best = best.min(a.0.distance(b.0));
            }
        }
    }
    best
}

fn params(target: u32) -> StampParams<'static> {
    StampParams {
        target_count: target,
        seed: 11,
        ..StampParams::default()
    }
}

#[test]
fn count_hits_target_on_uniform_and_graded_meshes() {
    for (name, m) in [
        ("sphere", sphere(24, 48)),
        ("graded 1e4", graded_plane(40, 100.0)),
        ("coarse plane", graded_plane(2, 1.0)),
        ("two triangles", graded_plane(1, 1.0)),
    ] {
        for target in [10u32, 30, 100, 500, 3000, 20000] {
            let (roots, report) = run(m.mesh(), &params(target));
            // the stamp lands in [target, target * 1.02] and the surplus
            // is trimmed by rank, so the count is exact
            assert_eq!(roots.len(), target as usize, "{name}: {report:?}");
        }
    }
}

/// A target of a few roots on a few faces can have a pass stamp none
/// at all (the window of the tile each chart takes misses every
/// point); the correction goes on from there instead of keeping zero.
#[test]
fn tiny_targets_are_met_on_small_meshes() {
    for m in [graded_plane(1, 1.0), graded_plane(4, 20.0), sphere(4, 8)] {
        for target in 1..=4 {
            for seed in 0..200 {
                let (roots, report) = run(
                    m.mesh(),
                    &StampParams {
                        seed,
                        ..params(target)
                    },
                );
                assert_eq!(roots.len(), target as usize, "seed {seed}: {report:?}");
            }
        }
    }
}

/// Barycentrics from the signed areas can round a hair past an edge for
/// a point the edge tests take; every root still lies in its triangle.
/// The mesh is the C contract test's sphere (a duplicated seam column,
/// pole rows of repeated points), where seed 42 once put a root a
/// rounding error outside.
#[test]
fn roots_lie_in_their_triangle_on_a_seamed_sphere() {
    let m = seamed_sphere(24, 48);
    for seed in [42, 43] {
        // `run` checks every root
        run(
            m.mesh(),
            &StampParams {
                seed,
                ..params(3000)
            },
        );
    }
}

#[test]
fn no_two_roots_closer_than_the_radius_and_lod_prefixes_spread() {
    let m = sphere(16, 32);
    let mesh = m.mesh();
    let (roots, report) = run(mesh, &params(4000));
    let min = min_spacing(&mesh, &roots);
    assert!(
        min >= report.radius * 0.999,
        "min {min} < r {}",
        report.radius
    );
    let n = roots.len();
    for frac in [2usize, 4, 16] {
        let prefix: Vec<Root> = roots
            .iter()
            .copied()
            .filter(|r| (r.rank as usize) < n / frac)
            .collect();
        let spacing = min_spacing(&mesh, &prefix);
        // a Poisson set of n/frac roots has spacing ~ r * sqrt(frac)
        let expect = report.radius * libm::sqrtf(frac as f32);
        assert!(spacing >= 0.5 * expect, "1/{frac}: {spacing} vs {expect}");
    }
    let mut ranks: Vec<u32> = roots.iter().map(|r| r.rank).collect();
    ranks.sort_unstable();
    assert!(ranks.iter().enumerate().all(|(i, &r)| r == i as u32));
    assert!(roots.iter().enumerate().all(|(i, r)| r.id == i as u32));
}

/// A face holding more kept points than the fill tests in lanes
/// (`fill::OWN`, 1024, of those within reach of its cut edges) has its
/// darts tested point by point: two triangles of ~25,000 roots each
/// keep the spacing, the count and the fill's refills.
#[test]
fn faces_with_more_points_than_the_fills_lanes_keep_the_spacing() {
    let m = graded_plane(1, 1.0);
    let mesh = m.mesh();
    for seed in [3] {
        fill::POINT_BY_POINT.with(|c| c.set(0));
        let (roots, report) = run(
            mesh,
            &StampParams {
                seed,
                ..params(50_000)
            },
        );
        assert_eq!(roots.len(), 50_000, "{report:?}");
        // both faces' darts took the point-by-point path (the stamp may
        // take more than one pass)
        let faces = fill::POINT_BY_POINT.with(|c| c.get());
        assert!(faces >= 2, "{faces} faces tested point by point");
        assert!(report.filled > 0, "the fill added nothing: {report:?}");
        for face in 0..2 {
            let on = roots.iter().filter(|r| r.face == face).count();
            assert!(on > 20_000, "face {face}: {on} roots");
        }
        let min = min_spacing(&mesh, &roots);
        assert!(
            min >= report.radius * 0.999,
            "min {min} < r {}",
            report.radius
        );
    }
}

#[test]
fn shells_closer_than_the_radius_keep_the_spacing_between_them() {
    // two parallel sheets facing the same way, a grid cell's boundary
    // (z = 0) between them: no cell holds both sheets' faces
    let sheet = graded_plane(6, 1.0);
    let mut m = sheet.clone();
    let offset = sheet.p.len() as u32;
    m.p.iter_mut().for_each(|p| p[2] = -0.005);
    m.p.extend(sheet.p.iter().map(|p| [p[0], p[1], 0.005]));
    m.t.extend(sheet.t.iter().map(|t| t.map(|v| v + offset)));
    m.uv.extend(&sheet.uv);
    let mesh = m.mesh();
    let (roots, report) = run(mesh, &params(2000));
    assert!(
        report.radius > 0.01,
        "the sheets are closer than the radius: {report:?}"
    );
    let min = min_spacing(&mesh, &roots);
    assert!(
        min >= report.radius * 0.999,
        "min {min} < r {}",
        report.radius
    );
}

/// Every pair of kept points, on any two triangles, is at least the
/// spacing of the finer of their two LOD levels apart (in units of the
/// pair's clash distance, up to the bend of linked edges), on a curved
/// mesh of many charts with two densities.
#[test]
fn each_lod_level_keeps_its_spacing_across_triangles() {
    let m = sphere(16, 32);
    let mesh = m.mesh();
    let values: Vec<f32> =
        m.p.iter()
            .map(|p| if p[1] < 0.0 { 0.4 } else { 1.0 })
            .collect();
    with_candidates(mesh, &graded(&values), |stamper, scratch, mut cands| {
        let kept = stamper.prune(&mut cands, scratch).unwrap();
        let cands = &cands[..kept];
        // the tile's levels, which rank stamps too large for elimination
        stamper
            .assign_levels(cands, scratch, &mut |_| Ok(()))
            .unwrap();
        let raised = check_lod_spacing(stamper, cands, &scratch.level[..kept]);
        assert!(raised > 0, "no level was raised: nothing to check");
    });
}

/// A triangle wider than the tile holds copies of the tile's coarsest
/// points one tile apart, closer than their steps' spacing (wider than
/// the tile): the later copy takes a finer level. (A property test
/// found it on a height field of two cells.)
#[test]
fn copies_of_the_tile_on_one_wide_triangle_part() {
    let m = graded_plane(1, 1.0);
    for seed in [11, 12, 13] {
        let p = StampParams {
            seed,
            ..params(6000)
        };
        with_candidates(m.mesh(), &p, |stamper, scratch, mut cands| {
            let side = TILE_SIDE as f32 * stamper.radius;
            assert!(
                side < 0.5,
                "the triangles are not wider than the tile: {side}"
            );
            let kept = stamper.prune(&mut cands, scratch).unwrap();
            let cands = &cands[..kept];
            stamper
                .assign_levels(cands, scratch, &mut |_| Ok(()))
                .unwrap();
            let wide = |c: &Candidate| {
                let t = c.level as usize * LEVEL_STEPS + c.step as usize;
                tile::step_spacing(t / LEVEL_STEPS, t % LEVEL_STEPS) > TILE_SIDE as f32
            };
            assert!(cands.iter().filter(|c| wide(c)).count() > 2);
            check_lod_spacing(stamper, cands, &scratch.level[..kept]);
        });
    }
}

/// Checks the LOD spacing of every pair of kept candidates (see above):
/// the spacing of the finer of their steps; returns how many candidates
/// left their tile step.
fn check_lod_spacing(stamper: &Stamper, cands: &[Candidate], levels: &[u8]) -> usize {
    let mut raised = 0;
    let tile_step = |c: &Candidate| c.level as usize * LEVEL_STEPS + c.step as usize;
    for (c, &l) in cands.iter().zip(levels) {
        assert!(l as usize >= tile_step(c) && (l as usize) < LOD_LEVELS * LEVEL_STEPS);
        raised += (l as usize > tile_step(c)) as usize;
    }
    let at = |c: &Candidate| position(&stamper.mesh, c);
    for (i, a) in cands.iter().enumerate() {
        for (b, &lb) in cands[i + 1..].iter().zip(&levels[i + 1..]) {
            let (fa, fb) = (
                &stamper.faces[a.face as usize],
                &stamper.faces[b.face as usize],
            );
            if Vec3::from(fa.normal).dot(Vec3::from(fb.normal)) <= 0.0 {
                continue;
            }
            let t = levels[i].max(lb) as usize;
            let spacing = tile::step_spacing(t / LEVEL_STEPS, t % LEVEL_STEPS);
            let r = stamper.radius / fa.scale.max(fb.scale);
            let d = at(a).distance(at(b));
            assert!(
                d >= spacing * r * 0.999,
                "steps {} and {lb}: {d} < {spacing} * {r}",
                levels[i],
            );
        }
    }
    raised
}

/// The position the passes compute for `c`, to the bit.
fn position(mesh: &Mesh, c: &Candidate) -> Vec3 {
    Vec3::from(Near::new(c, 0, &face_frame(mesh, c.face as usize)).position)
}

/// 3000 roots over a per-vertex density map.
fn graded(values: &[f32]) -> StampParams<'_> {
    StampParams {
        density: ScalarMap::PerVertex(Strided::from_slice(values)),
        ..params(3000)
    }
}

/// Stamps one pass of 3000 roots on `mesh` with per-vertex density
/// `values` and hands the stamper, its scratch and the candidates to
/// `check`.
fn with_candidates(
    mesh: Mesh,
    p: &StampParams,
    check: impl FnOnce(&Stamper, &mut Scratch, Vec<Candidate>),
) {
    let mut buf = vec![0u8; required_bytes(&mesh, p).unwrap()];
    let mut arena = Arena::new(&mut buf);
    let stamper = Stamper::new(mesh, p, &mut arena).unwrap().unwrap();
    let faces = 0..mesh.triangle_count();
    let bound = stamper.candidate_bound(faces.clone());
    let mut scratch = Scratch::new(&mut arena, bound).unwrap();
    let mut cands = vec![Candidate::default(); bound];
    let n = stamper.stamp_faces(faces, &mut cands).unwrap();
    cands.truncate(n);
    check(&stamper, &mut scratch, cands);
}

#[test]
fn edge_pass_matches_a_brute_force_scan() {
    let m = graded_plane(12, 30.0);
    // gray and white faces: clash distances differ per pair
    let values: Vec<f32> =
        m.p.iter()
            .map(|p| if p[1] < 0.4 { 0.3 } else { 1.0 })
            .collect();
    with_candidates(m.mesh(), &graded(&values), check_edge_pass);
}

fn check_edge_pass(stamper: &Stamper, scratch: &mut Scratch, mut cands: Vec<Candidate>) {
    let n = cands.len();
    let at = |c: &Candidate| position(&stamper.mesh, c);
    let mut expect: Vec<Candidate> = Vec::new();
    for c in &cands {
        let clash = c.near_edge()
            && expect.iter().any(|k| {
                let (fk, fc) = (
                    &stamper.faces[k.face as usize],
                    &stamper.faces[c.face as usize],
                );
                let r = stamper.radius / fk.scale.max(fc.scale);
                k.face != c.face
                    && k.near_edge()
                    && Vec3::from(fk.normal).dot(Vec3::from(fc.normal)) > 0.0
                    && at(k).distance_squared(at(c)) < r * r
            });
        if !clash {
            expect.push(*c);
        }
    }
    let kept = stamper.prune(&mut cands, scratch).unwrap();
    assert!(kept < n, "the pass removed nothing to compare");
    assert_eq!(&cands[..kept], &expect[..]);
}

#[test]
fn progress_rises_to_one_and_a_false_return_cancels_with_nothing_written() {
    let m = graded_plane(30, 10.0);
    let mesh = m.mesh();
    let p = params(6000);
    let (reference, report) = run(mesh, &p);
    let mut buf = vec![0u8; required_bytes(&mesh, &p).unwrap()];
    let mut out = vec![Root::default(); max_roots(&mesh, &p).unwrap()];
    let mut seen = Vec::new();
    let (n, again) = stamp_with_progress(mesh, &p, &mut Arena::new(&mut buf), &mut out, &mut |f| {
        seen.push(f);
        true
    })
    .unwrap();
    assert_eq!((&out[..n], again), (&reference[..], report));
    assert!(seen.windows(2).all(|w| w[0] <= w[1]), "{seen:?}");
    assert_eq!((seen[0], *seen.last().unwrap()), (0.0, 1.0));
    // placement chunks, the edge pass and every LOD level report
    assert!(seen.len() >= LOD_LEVELS + 2, "{seen:?}");
    for stop in [1, seen.len() / 2, seen.len()] {
        let mut calls = 0;
        let mut untouched = vec![Root::default(); out.len()];
        let result = stamp_with_progress(
            mesh,
            &p,
            &mut Arena::new(&mut buf),
            &mut untouched,
            &mut |_| {
                calls += 1;
                calls != stop
            },
        );
        assert_eq!(result, Err(Error::Cancelled));
        assert_eq!(calls, stop);
        assert!(untouched.iter().all(|r| *r == Root::default()));
    }
}

#[test]
fn a_flat_chart_is_one_piece_of_the_tile() {
    // a flat plane unfolds onto itself: every candidate, on either side
    // of any edge, is a point of one Poisson set, and a tile point on a
    // shared edge goes to exactly one of its two faces
    let m = graded_plane(10, 1.0);
    // few enough roots that the chart reaches across the whole plane
    with_candidates(m.mesh(), &params(2000), |stamper, _, cands| {
        assert!(stamper
            .places
            .iter()
            .all(|t| t.offset == stamper.places[0].offset));
        let at = |c: &Candidate| position(&stamper.mesh, c);
        let mut closest = f32::INFINITY;
        for (i, a) in cands.iter().enumerate() {
            for b in &cands[i + 1..] {
                closest = closest.min(at(a).distance(at(b)));
            }
        }
        assert!(
            closest >= stamper.radius * 0.9999,
            "{closest} vs {}",
            stamper.radius
        );
        assert!(cands.iter().all(|c| c.near_levels as usize <= LOD_LEVELS));
    });
}

#[test]
fn an_output_of_exactly_the_count_is_enough() {
    let m = sphere(12, 24);
    // stamped once into room for the bound
    with_candidates(m.mesh(), &params(3000), |stamper, _, roomy| {
        let (faces, n) = (0..stamper.mesh.triangle_count(), roomy.len());
        let mut exact = vec![Candidate::default(); n];
        assert_eq!(stamper.stamp_faces(faces.clone(), &mut exact), Ok(n));
        assert_eq!(exact, roomy);
        let mut short = vec![Candidate::default(); n - 1];
        assert_eq!(
            stamper.stamp_faces(faces, &mut short),
            Err(Error::OutputTooSmall {
                needed: n,
                available: n - 1
            })
        );
    });
}

#[test]
fn identical_for_any_face_chunking() {
    let m = graded_plane(30, 10.0);
    let mesh = m.mesh();
    let p = params(6000);
    let (reference, _) = run(mesh, &p);
    for chunks in [2usize, 7, 64] {
        let mut buf = vec![0u8; required_bytes(&mesh, &p).unwrap()];
        let mut arena = Arena::new(&mut buf);
        let mut stamper = Stamper::new(mesh, &p, &mut arena).unwrap().unwrap();
        let faces = mesh.triangle_count();
        let bound = stamper.candidate_bound(0..faces);
        let mut scratch = Scratch::new(&mut arena, bound).unwrap();
        let mut cands = vec![Candidate::default(); bound];
        let kept = loop {
            let mut n = 0;
            for c in 0..chunks {
                let range = c * faces / chunks..(c + 1) * faces / chunks;
                let mut part = vec![Candidate::default(); stamper.candidate_bound(range.clone())];
                let k = stamper.stamp_faces(range, &mut part).unwrap();
                cands[n..n + k].copy_from_slice(&part[..k]);
                n += k;
            }
            let kept = stamper.prune(&mut cands[..n], &mut scratch).unwrap();
            let kept = stamper.fill(&mut cands, kept, &mut scratch).unwrap();
            if stamper.converged(n, kept) {
                break kept;
            }
        };
        let mut out = vec![Root::default(); stamper.output_count(kept)];
        stamper
            .finish(&cands[..kept], &mut scratch, &mut out)
            .unwrap();
        assert_eq!(out.len(), reference.len(), "{chunks} chunks: count");
        let first = out.iter().zip(&reference).position(|(a, b)| a != b);
        assert!(
            first.is_none(),
            "{chunks} chunks differ at {first:?}: {:?} vs {:?}",
            first.map(|i| out[i]),
            first.map(|i| reference[i])
        );
    }
}

#[test]
fn density_map_scales_and_bald_regions_stay_bald() {
    let m = graded_plane(20, 1.0);
    let mesh = m.mesh();
    // left half black, right half white
    let values: Vec<f32> =
        m.p.iter()
            .map(|p| if p[0] < 0.5 { 0.0 } else { 1.0 })
            .collect();
    let mut p = params(4000);
    p.density = ScalarMap::PerVertex(Strided::from_slice(&values));
    let (roots, _) = run(mesh, &p);
    assert!(roots
        .iter()
        .all(|r| mesh.point(r.face as usize, r.u, r.v).x > 0.44));
    p.bald_below = 0.0;
    let (roots, _) = run(mesh, &p);
    let left = roots
        .iter()
        .filter(|r| mesh.point(r.face as usize, r.u, r.v).x < 0.45)
        .count();
    let right = roots
        .iter()
        .filter(|r| mesh.point(r.face as usize, r.u, r.v).x > 0.55)
        .count();
    // black = half size: a quarter of the density
    let ratio = left as f32 / right as f32;
    assert!((ratio - 0.25).abs() < 0.05, "left/right = {ratio}");
}

/// Oler's bound holds for every face, from radii far larger than the
/// faces to far smaller, where it comes within the tile's packing density.
#[test]
fn no_face_takes_more_points_than_its_bound() {
    for m in [graded_plane(12, 100.0), sphere(12, 24)] {
        let mesh = m.mesh();
        for radius in [0.5, 0.05, 0.01, 0.002] {
            let params = StampParams {
                radius,
                seed: 5,
                ..StampParams::default()
            };
            let mut buf = vec![0u8; required_bytes(&mesh, &params).unwrap()];
            let mut arena = Arena::new(&mut buf);
            let stamper = Stamper::new(mesh, &params, &mut arena).unwrap().unwrap();
            let faces = mesh.triangle_count();
            let mut out = vec![Candidate::default(); stamper.candidate_bound(0..faces)];
            let (mut taken, mut bound) = (0, 0);
            for f in 0..faces {
                let b = stamper.candidate_bound(f..f + 1);
                let n = stamper.stamp_faces(f..f + 1, &mut out).unwrap();
                assert!(n <= b, "face {f} at radius {radius}: {n} > {b}");
                (taken, bound) = (taken + n, bound + b);
            }
            let share = taken as f32 / bound as f32;
            let packing = TILE.density() / HEX_PACKING as f32;
            assert!(
                radius > 0.005 || share > 0.9 * packing,
                "{taken} of {bound} at {radius}"
            );
        }
    }
}

#[test]
fn a_fixed_radius_keeps_every_root_and_its_spacing() {
    let m = sphere(16, 32);
    let mesh = m.mesh();
    let (white, report) = run(mesh, &params(3000));
    let fixed = |density: ScalarMap<'static>| StampParams {
        radius: report.radius,
        density,
        bald_below: 0.0,
        ..params(0)
    };
    let (same, r2) = run(mesh, &fixed(ScalarMap::Constant(1.0)));
    assert_eq!((r2.trimmed, r2.passes), (0, 1));
    assert!(min_spacing(&mesh, &same) >= report.radius * 0.999);
    // uniform gray 0.5 with black = half size: scale 0.75, density 0.5625
    let (gray, _) = run(mesh, &fixed(ScalarMap::Constant(0.5)));
    let ratio = gray.len() as f32 / same.len() as f32;
    assert!((ratio - 0.5625).abs() < 0.05, "gray/white = {ratio}");
    assert!(white.len() == 3000 && (same.len() as f32 / 3000.0 - 1.0).abs() < 0.06);
}

#[test]
fn rejects_bad_input_before_writing() {
    let m = sphere(8, 16);
    let mut bad = m.p.clone();
    bad[3][1] = f32::NAN;
    let mesh = Mesh::new(Strided::from_slice(&bad), Strided::from_slice(&m.t));
    assert!(matches!(
        required_bytes(&mesh, &params(100)),
        Err(Error::NonFinite { .. })
    ));
    let mesh = m.mesh();
    let need = required_bytes(&mesh, &params(100)).unwrap();
    let mut out = vec![Root::default(); 100];
    // too small for the stamper itself, and big enough for it but not
    // for the passes: both report the whole need
    let passes = passes_bytes(candidates_bound(&mesh, &params(100)).unwrap());
    for size in [100, need - passes] {
        let mut buf = vec![0u8; size];
        let mut arena = Arena::new(&mut buf);
        let err = stamp(mesh, &params(100), &mut arena, &mut out).unwrap_err();
        assert_eq!(
            err,
            Error::CapacityExceeded {
                needed: need,
                available: size
            }
        );
    }
    assert!(out.iter().all(|r| *r == Root::default()));
    let mut p = params(100);
    p.black_scale = 0.0;
    assert!(matches!(
        required_bytes(&mesh, &p),
        Err(Error::InvalidArgument(_))
    ));
}

/// A height field over a jittered, warped grid of `n` x `m` cells:
/// vertex `(i, j)` moves by `jitter[j * (n + 1) + i]` (in quarter
/// cells; border vertices stay on the border), `x` and `y` go through
/// `x^warp[0]` and `y^warp[1]` (triangle areas then vary by up to 10^5),
/// cell `c` is split along the diagonal `flip[c]` picks, and `z` is a
/// product of two waves whose slopes stay below 0.9.
fn wavy_field(
    (n, m): (usize, usize),
    warp: [f32; 2],
    jitter: &[(f32, f32)],
    flip: &[bool],
    [f1, f2, p1, p2]: [f32; 4],
) -> crate::testmesh::TestMesh {
    use core::f32::consts::TAU;
    let amplitude = 0.1 / f1.max(f2);
    let mut p = vec![];
    let mut uv = vec![];
    // coordinate `k` of `0..=last`, moved by `d` quarter cells, warped
    let at = |k: usize, last: usize, d: f32, warp: f32| {
        let t = if k == 0 || k == last { 0.0 } else { 0.25 * d };
        ((k as f32 + t) / last as f32).powf(warp)
    };
    for j in 0..=m {
        for i in 0..=n {
            let (dx, dy) = jitter[j * (n + 1) + i];
            let (x, y) = (at(i, n, dx, warp[0]), at(j, m, dy, warp[1]));
            let z = amplitude * (TAU * f1 * x + p1).sin() * (TAU * f2 * y + p2).cos();
            p.push([x, y, z]);
            uv.push([x, y]);
        }
    }
    crate::testmesh::TestMesh {
        p,
        t: crate::testmesh::grid_triangles(n, m, |c| flip[c]),
        uv,
        n: vec![],
    }
}

/// The stamp's guarantees on `mesh` (whose edge-adjacent faces bend
/// by less than 90 degrees, see `prune`) for `params`: the count is the
/// target, every root lies on a stamped face, no two same-facing roots
/// are closer than their pair's disk radius, every LOD level keeps its
/// spacing, and splitting the faces at `cuts` (shares of the face
/// count) stamps the same points.
fn check_guarantees(
    mesh: Mesh,
    params: &StampParams,
    cuts: &[f32],
) -> Result<(), proptest::test_runner::TestCaseError> {
    // scale and normal of each face, and each root's point, made once
    // for the pair loop
    let faces: Vec<(f32, Vec3)> = (0..mesh.triangle_count())
        .map(|f| {
            let face = FaceSetup::new(&mesh, params, f).face;
            (face.scale, Vec3::from(face.normal))
        })
        .collect();
    let stamped = faces.iter().any(|&(scale, _)| scale > 0.0);
    let (roots, report) = run(mesh, params);
    let target = params.target_count as usize;
    prop_assert_eq!(
        roots.len(),
        if stamped { target } else { 0 },
        "{:?}",
        report
    );
    let points: Vec<Vec3> = roots
        .iter()
        .map(|r| mesh.point(r.face as usize, r.u, r.v))
        .collect();
    for (i, (a, pa)) in roots.iter().zip(&points).enumerate() {
        let (scale_a, normal_a) = faces[a.face as usize];
        prop_assert!(scale_a > 0.0, "root on a bald face");
        for (b, pb) in roots[i + 1..].iter().zip(&points[i + 1..]) {
            let (scale_b, normal_b) = faces[b.face as usize];
            if normal_a.dot(normal_b) <= 0.0 {
                continue;
            }
            let r = report.radius / scale_a.max(scale_b);
            let d = pa.distance(*pb);
            prop_assert!(d >= 0.999 * r, "{a:?} and {b:?}: {d} < {r}");
        }
    }
    if !stamped {
        return Ok(());
    }
    with_candidates(mesh, params, |stamper, scratch, mut cands| {
        let faces = mesh.triangle_count();
        let mut bounds: Vec<usize> = cuts.iter().map(|c| (c * faces as f32) as usize).collect();
        bounds.extend([0, faces]);
        bounds.sort_unstable();
        let mut chunked = vec![];
        for w in bounds.windows(2) {
            let mut part = vec![Candidate::default(); stamper.candidate_bound(w[0]..w[1])];
            let k = stamper.stamp_faces(w[0]..w[1], &mut part).unwrap();
            chunked.extend_from_slice(&part[..k]);
        }
        assert_eq!(chunked, cands, "chunks at {bounds:?}");
        let kept = stamper.prune(&mut cands, scratch).unwrap();
        let cands = &cands[..kept];
        stamper
            .assign_levels(cands, scratch, &mut |_| Ok(()))
            .unwrap();
        check_lod_spacing(stamper, cands, &scratch.level[..kept]);
    });
    Ok(())
}

/// Whether two faces of `m` that share an edge bend by 90 degrees or
/// more (a crease the spacing guarantee does not cover).
fn creased(m: &crate::testmesh::TestMesh) -> bool {
    let mesh = m.mesh();
    let mut faces = std::collections::HashMap::<(u32, u32), Vec<usize>>::new();
    for (f, t) in m.t.iter().enumerate() {
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            faces.entry((a.min(b), a.max(b))).or_default().push(f);
        }
    }
    let normal = |f: usize| mesh.face_normal(f);
    faces
        .values()
        .any(|f| f.len() == 2 && normal(f[0]).dot(normal(f[1])) <= 0.0)
}

/// A `rows` x `cols` UV sphere with radial bumps (`amplitude` of
/// waves `k` around and `l` along the axis), stretched by `stretch`
/// across the axis: a closed surface with poles, seams and, when thin
/// enough, two sides whose normals oppose.
fn blob(
    (rows, cols): (usize, usize),
    (amplitude, k, l): (f32, u32, u32),
    stretch: (f32, f32),
) -> crate::testmesh::TestMesh {
    let mut m = sphere(rows, cols);
    for p in m.p.iter_mut() {
        let [x, y, z] = *p;
        let around = libm::atan2f(z, x);
        let s = 1.0 + amplitude * libm::sinf(k as f32 * around) * libm::cosf(l as f32 * 3.0 * y);
        *p = [x * s * stretch.0, y * s, z * s * stretch.1];
    }
    m
}

use proptest::prelude::*;

/// Cells per side of [`wavy_field`] in the property tests.
const MAX_CELLS: usize = 16;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// [`check_guarantees`] on random height fields (one sheet, every
    /// face same-facing) with random density maps, areas that vary by
    /// up to 10^5 and degenerate faces.
    #[test]
    fn random_height_fields_keep_every_stamp_guarantee(
        cells in (1..=MAX_CELLS, 1..=MAX_CELLS),
        warp in (1.0f32..3.0, 1.0f32..3.0),
        jitter in prop::collection::vec((-1.0f32..1.0, -1.0f32..1.0), (MAX_CELLS + 1).pow(2)),
        flip in prop::collection::vec(any::<bool>(), MAX_CELLS.pow(2)),
        waves in (0.3f32..2.0, 0.3f32..2.0, 0.0f32..6.3, 0.0f32..6.3),
        density in prop::collection::vec(0.0f32..=1.0, (MAX_CELLS + 1).pow(2)),
        gray in any::<bool>(),
        black_scale in MIN_BLACK_SCALE..=1.0f32,
        bald_below in prop::sample::select(vec![0.0f32, 1.0 / 512.0, 0.3]),
        target in 1u32..1500,
        seed in any::<u64>(),
        cuts in prop::collection::vec(0.0f32..1.0, 0..5),
        collapse in prop::collection::vec(0usize..(MAX_CELLS + 1).pow(2), 0..3),
    ) {
        let mut m = wavy_field(cells, [warp.0, warp.1], &jitter, &flip, [waves.0, waves.1, waves.2, waves.3]);
        // a vertex moved onto the next one: the faces with both are
        // degenerate (skipped)
        for &v in &collapse {
            let v = v % (m.p.len() - 1);
            m.p[v] = m.p[v + 1];
        }
        // every face tilts by less than 41 degrees, so every pair of
        // faces is same-facing and every bend is under 90 degrees: the
        // surfaces the spacing guarantee covers (a long thin face can
        // be steeper than the waves, so flatten them until none is)
        let tilted = |m: &crate::testmesh::TestMesh| {
            let mesh = m.mesh();
            (0..mesh.triangle_count())
                .any(|f| !mesh.shape(f).degenerate && mesh.face_normal(f).z <= 0.75)
        };
        for _ in 0..20 {
            if !tilted(&m) {
                break;
            }
            m.p.iter_mut().for_each(|p| p[2] *= 0.5);
        }
        // a collapse can fold a face over
        prop_assume!(!tilted(&m));
        let mesh = m.mesh();
        let values = &density[..m.p.len()];
        let params = StampParams {
            target_count: target,
            seed,
            density: if gray {
                ScalarMap::PerVertex(Strided::from_slice(values))
            } else {
                ScalarMap::Constant(1.0)
            },
            black_scale,
            bald_below,
            ..StampParams::default()
        };
        check_guarantees(mesh, &params, &cuts)?;
    }

    /// The same on closed bumpy blobs without creases, whose thin
    /// parts have two sides that never clash.
    #[test]
    fn random_blobs_keep_every_stamp_guarantee(
        cells in (3usize..24, 3usize..40),
        bumps in (0.0f32..0.3, 1u32..4, 1u32..4),
        stretch in (0.3f32..3.0, 0.3f32..3.0),
        density in prop::collection::vec(0.0f32..=1.0, 24 * 40),
        gray in any::<bool>(),
        target in 1u32..1500,
        seed in any::<u64>(),
        cuts in prop::collection::vec(0.0f32..1.0, 0..5),
    ) {
        let m = blob(cells, bumps, stretch);
        prop_assume!(!creased(&m));
        let params = StampParams {
            target_count: target,
            seed,
            density: if gray {
                ScalarMap::PerVertex(Strided::from_slice(&density[..m.p.len()]))
            } else {
                ScalarMap::Constant(1.0)
            },
            ..StampParams::default()
        };
        check_guarantees(m.mesh(), &params, &cuts)?;
    }
}
