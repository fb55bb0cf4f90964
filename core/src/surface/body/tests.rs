use super::*;
use crate::rng::{self, Purpose};
use crate::testmesh::{graded_plane, sphere};

fn build<'a>(mesh: &Mesh, buf: &'a mut Vec<u8>) -> Body<'a> {
    *buf = vec![0u8; Body::required_bytes(mesh).unwrap()];
    Body::new(mesh, &mut Arena::new(buf)).unwrap()
}

/// The body of `mesh` at `density` cells per triangle, in `buf`.
fn build_at<'a>(mesh: &Mesh, density: f32, buf: &'a mut Vec<u8>) -> Body<'a> {
    let mut rim_memory = vec![0u8; Rim::required_bytes(mesh)];
    let rim = Rim::new(mesh, &mut Arena::new(&mut rim_memory)).unwrap();
    let plan = BodyPlan::with_density(mesh, &rim, density).unwrap();
    *buf = vec![0u8; plan.build_bytes(mesh, &rim)];
    Body::build(&plan, mesh, &rim, &mut Arena::new(buf)).unwrap()
}

/// One edge at a time, with branches: what [`edges`] computes in lanes.
fn edge(a: [f32; 3], b: [f32; 3], p: [f32; 3]) -> (f32, bool) {
    let swap = (a[1], a[2]) > (b[1], b[2]);
    let (a, b) = if swap { (b, a) } else { (a, b) };
    let (dy, dz) = (b[1] - a[1], b[2] - a[2]);
    let e = dy * (p[2] - a[2]) - dz * (p[1] - a[1]);
    let positive = if e != 0.0 {
        e > 0.0
    } else if dy != 0.0 {
        dy > 0.0
    } else {
        dz > 0.0
    };
    if swap {
        (-e, !positive)
    } else {
        (e, positive)
    }
}

/// [`crossing_within`] for any line: none for a line outside the
/// bounds.
fn crossing<const AXIS: usize>(t: &Stored, p: Vec3) -> Option<(f32, i32)> {
    let (j, k) = ((AXIS + 1) % 3, (AXIS + 2) % 3);
    let (lo, hi) = t.bounds();
    if p[j] < lo[j] || p[j] > hi[j] || p[k] < lo[k] || p[k] > hi[k] {
        return None;
    }
    crossing_within::<AXIS>(t, p)
}

/// A stored triangle for the tests of what reads only its corners.
fn corners_only(corners: [Vec3; 3]) -> Stored {
    let [a, b, c] = corners.map(|v| v.extend(0.0).into());
    Stored {
        first: a,
        rest: [b, c],
        ..Stored::default()
    }
}

/// [`crossing`] from [`edge`].
fn crossing_by_edge<const AXIS: usize>(t: &Stored, p: Vec3) -> Option<(f32, i32)> {
    let (j, k) = ((AXIS + 1) % 3, (AXIS + 2) % 3);
    let (lo, hi) = t.bounds();
    if p[j] < lo[j] || p[j] > hi[j] || p[k] < lo[k] || p[k] > hi[k] {
        return None;
    }
    let turn = |v: [f32; 3]| [v[AXIS], v[j], v[k]];
    let [a, b, c] = t.corners();
    let (a, b, c, p) = (turn(a), turn(b), turn(c), turn(p.to_array()));
    let (w0, s0) = edge(b, c, p);
    let (w1, s1) = edge(c, a, p);
    let (w2, s2) = edge(a, b, p);
    if s0 != s1 || s1 != s2 {
        return None;
    }
    let sum = w0 + w1 + w2;
    Some((
        (w0 * a[0] + w1 * b[0] + w2 * c[0]) / sum,
        if s0 { -1 } else { 1 },
    ))
}

#[test]
fn slivers_are_listed_wherever_their_crossings_can_fall() {
    // three bands of 1,500 slivers (aspect ~300) from pole to pole, and
    // points within 0.01 of them, at a coarse and a fine grid
    let m = sphere(3, 1500);
    let mesh = m.mesh();
    for density in [2.0, 32.0] {
        let mut memory = vec![];
        let body = build_at(&mesh, density, &mut memory);
        let mut inside = 0;
        for i in 0..1500u64 {
            let r = |c| rng::unit(17, i, Purpose::Uniform, c);
            let f = ((r(0) * mesh.triangle_count() as f32) as usize).min(mesh.triangle_count() - 1);
            let (u, v) = (r(1), r(2));
            let (u, v) = if u + v > 1.0 {
                (1.0 - u, 1.0 - v)
            } else {
                (u, v)
            };
            let [a, b, c] = mesh.corners(f);
            let n = (b - a).cross(c - a).normalize();
            let p = a + (b - a) * u + (c - a) * v + n * (0.01 * (r(3) * 2.0 - 1.0));
            let w = winding(&mesh, p);
            if (w - 0.5).abs() < 1e-3 {
                continue;
            }
            assert_eq!(
                body.contains(p),
                w > 0.5,
                "{p}: winding {w}, density {density}"
            );
            inside += (w > 0.5) as usize;
        }
        assert!((400..1100).contains(&inside), "{inside}");
    }
}

#[test]
fn crossings_in_lanes_match_one_edge_at_a_time() {
    // small integer coordinates make lines through edges and vertices,
    // collinear and repeated corners common; the rest are arbitrary
    let mut checked = 0;
    for i in 0..400_000u64 {
        let mut next = {
            let mut k = 0u32;
            move || {
                k += 1;
                rng::unit(11, i, Purpose::Uniform, k)
            }
        };
        let exact = i % 2 == 0;
        let mut value = || {
            let u = next();
            if exact {
                libm::floorf(u * 4.0) - 1.0
            } else {
                u * 2.0 - 1.0
            }
        };
        let corners: [[f32; 3]; 3] = core::array::from_fn(|_| [value(), value(), value()]);
        let p = Vec3::new(value(), value(), value());
        let [a, b, c] = corners.map(Vec3::from);
        let t = corners_only([a, b, c]);
        let same = |x: Option<(f32, i32)>, y: Option<(f32, i32)>| match (x, y) {
            (Some((h, s)), Some((g, r))) => h.to_bits() == g.to_bits() && s == r,
            (None, None) => true,
            _ => false,
        };
        assert!(
            same(crossing::<0>(&t, p), crossing_by_edge::<0>(&t, p)),
            "{t:?} {p}"
        );
        assert!(
            same(crossing::<1>(&t, p), crossing_by_edge::<1>(&t, p)),
            "{t:?} {p}"
        );
        assert!(
            same(crossing::<2>(&t, p), crossing_by_edge::<2>(&t, p)),
            "{t:?} {p}"
        );
        checked += crossing_by_edge::<2>(&t, p).is_some() as u32;
    }
    assert!(checked > 10_000, "{checked} crossings");
}

#[test]
fn planes_cull_only_triangles_no_leg_crosses() {
    // slivers, a sphere moved far from the origin, a lattice of small
    // integers (points on edges and corners) and a sphere with a hole
    // (its cap's triangles culled too), at coarse to fine grids:
    // points on and within rounding of the surface, and in cells it
    // passes through, take the same winding number with the planes'
    // cull and without it
    let slivers = sphere(3, 1500);
    let mut far = sphere(12, 24);
    far.p.iter_mut().for_each(|p| p[0] += 3e4);
    let mut lattice = sphere(6, 8);
    lattice
        .p
        .iter_mut()
        .for_each(|p| *p = p.map(|c| libm::roundf(c * 8.0) * 0.5));
    let holed = holed_sphere(0.7);
    // (3e4 from the origin too: the body works relative to its grid's
    // corner, so the room for rounding is the mesh's, not the world's)
    let meshes = [
        (&slivers, 1.0f32, true),
        (&far, 1.0, true),
        (&lattice, 4.0, true),
        (&holed, 1.0, true),
    ];
    for (m, scale, culls) in meshes {
        let mesh = m.mesh();
        for density in [2.0, 8.0, 32.0] {
            let mut memory = vec![];
            let body = build_at(&mesh, density, &mut memory);
            let mut differs = 0;
            CULLED.with(|c| c.set(0));
            for i in 0..20_000u64 {
                let r = |c| rng::unit(23, i, Purpose::Uniform, c);
                let f =
                    ((r(0) * mesh.triangle_count() as f32) as usize).min(mesh.triangle_count() - 1);
                let [a, b, c] = mesh.corners(f);
                let (u, v) = match i % 4 {
                    // a corner, an edge's middle
                    0 => (0.0, 0.0),
                    1 => (0.5, 0.0),
                    _ => {
                        let (u, v) = (r(1), r(2));
                        if u + v > 1.0 {
                            (1.0 - u, 1.0 - v)
                        } else {
                            (u, v)
                        }
                    }
                };
                let n = (b - a).cross(c - a).normalize_or_zero();
                let off = [0.0, 1e-6, 1e-3, 0.05][(i / 4 % 4) as usize] * scale;
                let p = a + (b - a) * u + (c - a) * v + n * (off * (r(3) * 2.0 - 1.0));
                let culled = body.capped_winding(p);
                UNCULLED.with(|u| u.set(true));
                let all = body.capped_winding(p);
                UNCULLED.with(|u| u.set(false));
                differs += (culled != all) as usize;
            }
            assert_eq!(differs, 0, "density {density}");
            let culled = CULLED.with(|c| c.get());
            assert_eq!(culled > 1000, culls, "{culled} culled at density {density}");
        }
    }
}

#[test]
fn a_segment_is_blocked_where_it_meets_the_surface() {
    let m = sphere(24, 48);
    let mesh = m.mesh();
    let mut buf = vec![];
    let body = build(&mesh, &mut buf);
    let v = |x, y, z| Vec3::new(x, y, z);
    // through the sphere, into it, and out of it, along and across axes
    assert!(body.blocks(v(-2.0, 0.1, 0.2), v(2.0, 0.1, 0.2)));
    assert!(body.blocks(v(0.3, -1.5, 1.5), v(-0.2, 0.1, -0.1)));
    assert!(body.blocks(v(0.1, 0.2, 0.3), v(1.3, 1.2, -1.1)));
    // past it, short of it, and wholly inside it
    assert!(!body.blocks(v(-2.0, 1.2, 0.0), v(2.0, 1.2, 0.0)));
    assert!(!body.blocks(v(1.5, 1.5, 1.5), v(0.7, 0.7, 0.7)));
    assert!(!body.blocks(v(-0.5, 0.1, 0.2), v(0.5, -0.1, 0.0)));
    // from far outside the grid, and wholly outside it
    assert!(body.blocks(v(-1e4, 0.1, 0.2), v(1e4, 0.3, -0.2)));
    assert!(body.blocks(v(3e3, -2e3, 1e3), v(0.0, 0.0, 0.0)));
    assert!(!body.blocks(v(-1e4, 5.0, 0.0), v(1e4, 5.0, 0.0)));
    // a point, and segments with a NaN or infinite end, meet nothing
    assert!(!body.blocks(v(1.5, 0.0, 0.0), v(1.5, 0.0, 0.0)));
    assert!(!body.blocks(v(0.9, 0.1, 0.0), v(0.9, 0.1, 0.0)));
    assert!(!body.blocks(v(-2.0, 0.0, 0.0), v(f32::NAN, 0.0, 0.0)));
    assert!(!body.blocks(v(-2.0, 0.0, 0.0), v(f32::INFINITY, 0.0, 0.0)));
    // every chord between two points just outside opposite sides
    for i in 0..2000u64 {
        let r = |c| rng::unit(3, i, Purpose::Uniform, c) * 2.0 - 1.0;
        let dir = v(r(0), r(1), r(2)).normalize_or_zero();
        if dir == Vec3::ZERO {
            continue;
        }
        assert!(body.blocks(dir * 1.01, -dir * 1.01), "{dir}");
        assert!(!body.blocks(dir * 1.01, dir * 1.5), "{dir}");
    }
}

#[test]
fn sphere_inside_matches_the_radius() {
    let m = sphere(24, 48);
    let mesh = m.mesh();
    let mut buf = vec![];
    let body = build(&mesh, &mut buf);
    // the polyhedron lies between the inscribed and circumscribed radii
    let inner = (0..mesh.triangle_count())
        .filter(|&f| !mesh.is_degenerate(f))
        .map(|f| {
            let [a, ..] = mesh.corners(f);
            mesh.face_normal(f).dot(a).abs()
        })
        .fold(f32::INFINITY, f32::min);
    let mut checked = 0;
    for i in 0..200_000u64 {
        let r = |c| rng::unit(7, i, Purpose::Uniform, c) * 2.4 - 1.2;
        let p = Vec3::new(r(0), r(1), r(2));
        let d = p.length();
        if d < inner - 1e-4 {
            assert!(body.contains(p), "{p} at {d} is inside");
            checked += 1;
        } else if d > 1.0 + 1e-4 {
            assert!(!body.contains(p), "{p} at {d} is outside");
            checked += 1;
        }
    }
    assert!(checked > 190_000);
    // points on the grid's own lattice and on mesh vertices do not break the count
    for &v in m.p.iter() {
        let p = Vec3::from(v) * 0.999;
        assert!(body.contains(p), "{p} just inside a vertex");
        assert!(!body.contains(Vec3::from(v) * 1.001));
        // rays along x through the vertex itself (and its edges' ends)
        if v[0].abs() > 0.3 {
            assert!(
                body.contains(Vec3::new(0.0, v[1], v[2])),
                "ray through {v:?}"
            );
            assert!(
                !body.contains(Vec3::new(-1.2, v[1], v[2])),
                "ray through {v:?}"
            );
        }
    }
}

/// The generalized winding number of `mesh` at `p`, triangle by triangle.
fn winding(mesh: &Mesh, p: Vec3) -> f64 {
    let total: f64 = (0..mesh.triangle_count())
        .map(|f| {
            let [a, b, c] = mesh.corners(f);
            solid_angle(&corners_only([a, b, c]), p)
        })
        .sum();
    total / (4.0 * core::f64::consts::PI)
}

/// `contains` against the winding number, brute force, at random points
/// of the box `lo..hi` (points within `margin` of the threshold are
/// ties, left out); returns how many points were inside.
fn agrees_with_winding(mesh: &Mesh, lo: Vec3, hi: Vec3, points: u64, margin: f64) -> usize {
    let mut buf = vec![];
    let body = build(mesh, &mut buf);
    let mut inside = 0;
    for i in 0..points {
        let r = |c| rng::unit(5, i, Purpose::Uniform, c);
        let p = lo + (hi - lo) * Vec3::new(r(0), r(1), r(2));
        let w = winding(mesh, p);
        if (w - 0.5).abs() < margin {
            continue;
        }
        assert_eq!(body.contains(p), w > 0.5, "{p}: winding {w}");
        inside += (w > 0.5) as usize;
    }
    inside
}

#[test]
fn any_split_of_the_layers_builds_the_same_grid() {
    // a holed sphere: caps and near-cap cells too
    let m = holed_sphere(0.5);
    let mesh = m.mesh();
    let mut rim_memory = vec![0u8; Rim::required_bytes(&mesh)];
    let rim = Rim::new(&mesh, &mut Arena::new(&mut rim_memory)).unwrap();
    let plan = BodyPlan::of(&mesh, &rim).unwrap();
    let mut whole_memory = vec![0u8; plan.build_bytes(&mesh, &rim)];
    let whole = Body::build(&plan, &mesh, &rim, &mut Arena::new(&mut whole_memory)).unwrap();
    let n = whole.shape.dims[2];
    for cuts in [
        vec![0, n],
        vec![0, 0, n / 2, n],
        vec![0, 1, 2, n / 3, n - 1, n, n],
    ] {
        let mut memory = vec![0u8; plan.bytes()];
        let mut parts = Body::parts(&plan, &mesh, &rim, &mut Arena::new(&mut memory)).unwrap();
        // the references in memory of their own, as a host with
        // threads may give them
        let per = parts.layer_cells();
        let ranges: Vec<Range<usize>> = cuts.windows(2).map(|w| w[0]..w[1]).collect();
        let (grid, start, _, _) = parts.split();
        let totals: Vec<u64> = ranges
            .iter()
            .map(|l| grid.count(l.clone(), &mut start[l.start * per..l.end * per]))
            .collect();
        let total: u64 = totals.iter().sum();
        let mut refs_memory = vec![0u8; BodyParts::refs_bytes(total).unwrap()];
        // (a vector's memory is aligned: the bytes of the references
        // themselves, less one)
        let mut short = vec![0u8; 4 * total as usize - 1];
        // short memory is refused, and leaves the parts to try again
        assert!(matches!(
            parts.set_total(total, &mut Arena::new(&mut short)),
            Err(Error::CapacityExceeded { .. })
        ));
        parts
            .set_total(total, &mut Arena::new(&mut refs_memory))
            .unwrap();
        let (grid, start, refs, class) = parts.split();
        let mut base = 0u32;
        for (l, &total) in ranges.iter().zip(&totals) {
            let part = &mut refs[base as usize..(base + total as u32) as usize];
            grid.fill(
                l.clone(),
                base,
                &mut start[l.start * per..l.end * per],
                part,
            );
            base += total as u32;
        }
        for l in &ranges {
            grid.classify(l.clone(), start, &mut class[l.start * per..l.end * per]);
        }
        let body = parts.finish();
        assert!(body.start == whole.start, "{cuts:?}");
        assert!(body.refs == whole.refs, "{cuts:?}");
        assert!(body.class == whole.class, "{cuts:?}");
    }
    assert!(matches!(
        BodyParts::refs_bytes(u64::from(u32::MAX)),
        Err(Error::InvalidArgument(_))
    ));
}

/// A sphere with the triangles whose centroid has `y > cut` removed.
fn holed_sphere(cut: f32) -> crate::testmesh::TestMesh {
    let mut m = sphere(12, 24);
    let p = m.p.clone();
    m.t.retain(|t| t.iter().map(|&v| p[v as usize][1]).sum::<f32>() / 3.0 <= cut);
    m
}

#[test]
fn open_meshes_follow_the_generalized_winding_number() {
    // a small hole (an eye socket), a wide one (a bowl), and a sliver
    for cut in [0.9f32, 0.2, -0.6] {
        let m = holed_sphere(cut);
        let mesh = m.mesh();
        let inside = agrees_with_winding(&mesh, Vec3::splat(-1.3), Vec3::splat(1.3), 4000, 1e-4);
        assert!(inside > 50, "cut {cut}: {inside} inside");
    }
}

#[test]
fn intersecting_shells_and_a_shell_inside_another() {
    // a sphere, a second one overlapping it, and a small one inside the
    // first: inside one or more counts as inside
    let (a, b, c) = (sphere(10, 20), sphere(10, 20), sphere(6, 12));
    let mut p: Vec<[f32; 3]> = a.p.clone();
    p.extend(b.p.iter().map(|v| [v[0] + 0.8, v[1] * 0.7, v[2]]));
    p.extend(
        c.p.iter()
            .map(|v| [v[0] * 0.3 - 0.4, v[1] * 0.3, v[2] * 0.3]),
    );
    let mut t = a.t.clone();
    let shift = |m: &crate::testmesh::TestMesh, by: usize| {
        m.t.iter()
            .map(move |f| f.map(|v| v + by as u32))
            .collect::<Vec<_>>()
    };
    t.extend(shift(&b, a.p.len()));
    t.extend(shift(&c, a.p.len() + b.p.len()));
    let mesh = Mesh::new(
        crate::Strided::from_slice(&p),
        crate::Strided::from_slice(&t),
    );
    let lo = Vec3::new(-1.2, -1.2, -1.2);
    let hi = Vec3::new(2.0, 1.2, 1.2);
    assert!(agrees_with_winding(&mesh, lo, hi, 4000, 1e-4) > 500);
    let mut buf = vec![];
    let body = build(&mesh, &mut buf);
    // inside both spheres, and inside the inner one (winding 2)
    assert!(body.contains(Vec3::new(0.5, 0.0, 0.0)));
    assert!(body.contains(Vec3::new(-0.4, 0.0, 0.0)));
}

#[test]
fn open_and_degenerate_meshes() {
    let m = graded_plane(8, 1.0);
    let mesh = m.mesh();
    let mut buf = vec![];
    let body = build(&mesh, &mut buf);
    // a plane encloses nothing
    for p in [Vec3::new(0.5, 0.5, 0.01), Vec3::new(0.3, 0.7, -0.01)] {
        assert!(!body.contains(p));
    }
    let p = [[0.0f32; 3]; 3];
    let t = [[0u32, 1, 2]];
    let flat = Mesh::new(
        crate::Strided::from_slice(&p),
        crate::Strided::from_slice(&t),
    );
    assert!(matches!(
        Body::required_bytes(&flat),
        Err(Error::InvalidArgument(_))
    ));
    // a plan from another mesh is refused, not trusted
    let other = sphere(8, 16);
    let mut rim_memory = vec![0u8; Rim::required_bytes(&other.mesh())];
    let rim = Rim::new(&other.mesh(), &mut Arena::new(&mut rim_memory)).unwrap();
    let plan = BodyPlan::of(&other.mesh(), &rim).unwrap();
    let bytes = plan.build_bytes(&other.mesh(), &rim);
    let mut big = vec![0u8; bytes.max(Body::required_bytes(&mesh).unwrap())];
    assert!(matches!(
        Body::build(&plan, &mesh, &rim, &mut Arena::new(&mut big)),
        Err(Error::InvalidArgument(_))
    ));
    let mut small = vec![0u8; Body::required_bytes(&mesh).unwrap() - 1];
    assert!(matches!(
        Body::new(&mesh, &mut Arena::new(&mut small)),
        Err(Error::CapacityExceeded { .. })
    ));
}

/// A head-like mesh: a sphere with a wavy surface (so its rims are not
/// planar), open at a wide neck, a mouth and two eyes, with an eyeball
/// through each eye hole and a sliver hole.
fn holed_head() -> crate::testmesh::TestMesh {
    let mut m = sphere(24, 48);
    for v in &mut m.p {
        let around = libm::atan2f(v[2], v[0]);
        v[1] += 0.06 * libm::sinf(5.0 * around) * (1.0 - v[1] * v[1]);
    }
    let p = m.p.clone();
    let centroid = |t: &[u32; 3]| t.iter().map(|&v| Vec3::from(p[v as usize])).sum::<Vec3>() / 3.0;
    let holes = [
        (Vec3::new(0.0, -1.0, 0.0), 0.55),
        (Vec3::new(0.0, -0.4, 0.92), 0.3),
        (Vec3::new(0.35, 0.3, 0.89), 0.18),
        (Vec3::new(-0.35, 0.3, 0.89), 0.18),
    ];
    m.t.retain(|t| {
        let c = centroid(t);
        holes.iter().all(|(at, r)| c.distance(*at) > *r)
    });
    // a lone sliver hole: one more triangle gone
    m.t.remove(m.t.len() / 3);
    for x in [0.33f32, -0.33] {
        let eye = sphere(10, 20);
        let base = m.p.len() as u32;
        m.p.extend(
            eye.p
                .iter()
                .map(|v| [v[0] * 0.2 + x, v[1] * 0.2 + 0.28, v[2] * 0.2 + 0.8]),
        );
        m.t.extend(eye.t.iter().map(|t| t.map(|v| v + base)));
        m.uv.extend(eye.uv);
    }
    m
}

#[test]
fn near_a_hole_the_bounded_caps_answer_as_the_exact_ones() {
    // summed bounds and the caps' product of arguments against a cap
    // triangle at a time, at points all around the holes (many near the
    // threshold, none left out), at two densities; at the origin, and
    // small and large far from it (float32 differences there)
    let far = Vec3::new(0.8, 0.36, -0.48);
    for (scale, offset) in [(1.0, Vec3::ZERO), (0.125, far * 1e3), (12.5, far * 1e4)] {
        let mut m = holed_head();
        for v in &mut m.p {
            *v = (Vec3::from(*v) * scale + offset).to_array();
        }
        let mesh = m.mesh();
        let mut rim_memory = vec![0u8; Rim::required_bytes(&mesh)];
        let rim = Rim::new(&mesh, &mut Arena::new(&mut rim_memory)).unwrap();
        assert_eq!(rim.loop_count(), 5);
        let balls: Vec<(Vec3, f32)> = (0..5).map(|k| rim.ball(k, &mesh)).collect();
        for density in [2.0, 8.0] {
            let mut memory = vec![];
            let body = build_at(&mesh, density, &mut memory);
            EXACT_CAPS.with(|e| e.set(true));
            let mut exact_memory = vec![];
            let exact = build_at(&mesh, density, &mut exact_memory);
            let points: Vec<Vec3> = (0..40_000u64)
                .map(|i| {
                    let r = |c| rng::unit(23, i, Purpose::Uniform, c);
                    let d = Vec3::new(r(0), r(1), r(2)) * 2.0 - Vec3::ONE;
                    if i % 4 == 0 {
                        offset + d * 1.3 * scale
                    } else {
                        let (at, radius) = balls[(i as usize / 4) % balls.len()];
                        at + d * radius * 1.6
                    }
                })
                .collect();
            let want: Vec<bool> = points.iter().map(|&p| exact.contains(p)).collect();
            EXACT_CAPS.with(|e| e.set(false));
            let near = exact.class.iter().filter(|&&c| c & NEAR_CAP != 0).count();
            let tight = body.class.iter().filter(|&&c| c & NEAR_CAP != 0).count();
            assert!(tight < near, "{tight} near-cap cells, {near} before");
            FAST.with(|f| f.set([0; 3]));
            for (p, want) in points.iter().zip(&want) {
                assert_eq!(body.contains(*p), *want, "{p}, density {density}");
            }
            // most near-cap queries are settled without an arctangent per
            // cap triangle, by the bounds or by the product
            let [exactly, fast, bounded] = FAST.with(|f| f.get());
            assert!(
                exactly * 50 < fast && bounded < fast && 2 * bounded > fast,
                "{exactly} exactly, {fast} fast, {bounded} by bounds"
            );
            let inside = want.iter().filter(|&&w| w).count();
            assert!((5_000..30_000).contains(&inside), "{inside}");
        }
    }
}
