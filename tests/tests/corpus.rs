//! The corpus of production-like meshes (issue 48, ask 1) has what it
//! promises, and the stamp, through the C API, puts valid roots on every
//! representative mesh, far from the origin as at it, and spaces roots
//! that face the same air at creases. The `stamp_corpus` bench prints the
//! stamp's figures a row per mesh
//! (`cargo bench -p pelage-tests --bench stamp_corpus`).

use std::collections::HashMap;
use std::sync::OnceLock;

use glam::{DVec3, Vec3};

use pelage_core::surface::body::Body;
use pelage_core::{Arena, Root};
use pelage_tests::corpus::report::same_air_pairs;
use pelage_tests::corpus::{self, topology, CorpusMesh, Shape};
use pelage_tests::measure::r_hex;
use pelage_tests::quality::{empty_space, Skin};

/// Every mesh: the representative subset, then the whole corpus.
fn all() -> &'static [CorpusMesh] {
    static ALL: OnceLock<Vec<CorpusMesh>> = OnceLock::new();
    ALL.get_or_init(|| {
        let mut all = corpus::representative();
        all.extend(corpus::corpus());
        all
    })
}

/// One mesh per recipe at the origin (the topology is promised there: far
/// from the origin, rounding may put two vertices of a fine mesh in one
/// place: the `stamp_corpus` bench counts them).
fn at_origin() -> &'static [CorpusMesh] {
    static MESHES: OnceLock<Vec<CorpusMesh>> = OnceLock::new();
    MESHES.get_or_init(|| {
        let mut out: Vec<CorpusMesh> = Vec::new();
        for e in all() {
            let recipe = e.recipe.at_origin();
            if !out.iter().any(|o| o.recipe == recipe) {
                out.push(if e.recipe.is_placed() {
                    e.at_origin()
                } else {
                    e.clone()
                });
            }
        }
        out
    })
}

fn point(e: &CorpusMesh, i: u32) -> DVec3 {
    DVec3::from(e.mesh.positions[i as usize].map(f64::from))
}

fn is_corpus_head(e: &CorpusMesh) -> bool {
    matches!(e.recipe.shape, Shape::Head(_))
}

#[test]
fn numbers_and_indices_are_valid() {
    for e in all() {
        let (m, name) = (&e.mesh, &e.name);
        let nv = m.vertex_count();
        println!(
            "{name}: {nv} vertices, {} triangles, UVs {}",
            m.triangle_count(),
            e.has_uvs()
        );
        assert!(
            m.positions.iter().flatten().all(|x| x.is_finite()),
            "{name}: a position is not finite"
        );
        assert!(
            m.triangles.iter().flatten().all(|&i| (i as usize) < nv),
            "{name}: an index is out of range"
        );
        assert!(
            m.uvs.is_empty() || m.uvs.len() == nv,
            "{name}: {} UVs for {nv} vertices",
            m.uvs.len()
        );
        assert_eq!(e.has_uvs(), e.recipe.uvs, "{name}: UVs");
        assert!(
            m.uvs.iter().flatten().all(|x| (0.0..=1.0).contains(x)),
            "{name}: a UV is outside the unit square"
        );
        assert_eq!(
            m.normals.len(),
            if e.recipe.normals { nv } else { 0 },
            "{name}: normal count"
        );
        for n in &m.normals {
            let l = Vec3::from(*n).length();
            assert!((l - 1.0).abs() < 1e-5, "{name}: normal length {l}");
        }
        let mut used = vec![false; nv];
        m.triangles
            .iter()
            .flatten()
            .for_each(|&i| used[i as usize] = true);
        assert!(used.iter().all(|&u| u), "{name}: an unused vertex");
        // the parts cover the faces in order
        let mut end = 0;
        for p in &e.parts {
            assert_eq!(p.faces.start, end, "{name}: part {} starts late", p.name);
            assert!(!p.faces.is_empty(), "{name}: part {} is empty", p.name);
            end = p.faces.end;
        }
        assert_eq!(end, m.triangle_count(), "{name}: the parts miss faces");
    }
}

/// Each corpus head is open at the neck, the eyes and the mouth, and the
/// eye and mouth rims are far from planar (a flat cap over them misses
/// skin); the fin's two free edges form the one open chain.
#[test]
fn open_meshes_have_their_boundary_loops() {
    for e in at_origin() {
        let b = topology::boundary(&e.mesh);
        let planarity: Vec<f64> = b
            .loops
            .iter()
            .map(|l| topology::non_planarity(&topology::loop_points(&e.mesh, l)))
            .collect();
        println!(
            "{}: loops of {:?} edges, non-planarity {planarity:.3?}, {} chains",
            e.name,
            b.loops.iter().map(Vec::len).collect::<Vec<_>>(),
            b.chains
        );
        assert_eq!(
            (b.loops.len(), b.chains, b.pinched),
            (e.expect.boundary_loops, e.expect.open_chains, 0),
            "{}: (boundary loops, open chains, pinched pieces)",
            e.name
        );
        if is_corpus_head(e) {
            // the neck is a circle; the eyes and the mouth are not flat
            let bent = planarity.iter().filter(|&&p| p > 0.05).count();
            assert_eq!(
                bent, 3,
                "{}: eye and mouth rims with non-planarity > 0.05: {planarity:?}",
                e.name
            );
        }
    }
}

/// The eyeballs, teeth and ears are separate shells, and each cuts
/// through the head shell.
#[test]
fn separate_shells_cut_through_the_head() {
    for e in at_origin() {
        let (shells, count) = topology::shells(&e.mesh);
        assert_eq!(count, e.expect.shells, "{}: shells", e.name);
        for p in &e.parts {
            let s = shells[p.faces.start];
            assert!(
                shells[p.faces.clone()].iter().all(|&x| x == s),
                "{}: part {} spans shells",
                e.name,
                p.name
            );
        }
        if e.parts.len() > 1 {
            let head = e.parts[0].faces.clone();
            for p in &e.parts[1..] {
                assert_ne!(shells[p.faces.start], shells[0], "{}: {}", e.name, p.name);
                assert!(
                    topology::parts_intersect(&e.mesh, p.faces.clone(), head.clone()),
                    "{}: part {} at {:?} does not cut the head shell",
                    e.name,
                    p.name,
                    p.faces
                );
            }
        }
    }
}

/// The brow's step meets the skin at 90 degrees: the head shell has edges
/// whose faces' normals have a dot product within 0.1 of 0 (none on the
/// closed references).
#[test]
fn the_brow_is_a_90_degree_crease() {
    for e in at_origin() {
        let head = &e.parts[0].faces;
        let square: Vec<f64> = topology::creases(&e.mesh, 0.1)
            .into_iter()
            .filter(|c| head.contains(&(c.0 as usize)) && head.contains(&(c.1 as usize)))
            .filter(|c| c.2 >= -0.1)
            .map(|c| c.2)
            .collect();
        println!(
            "{}: {} head edges at 90 degrees (dot {:.3} .. {:.3})",
            e.name,
            square.len(),
            square.first().unwrap_or(&0.0),
            square.last().unwrap_or(&0.0)
        );
        if e.expect.crease {
            // both edges of the step, over most of the brow's meridians
            assert!(
                square.len() >= 40,
                "{}: {} edges at 90 degrees",
                e.name,
                square.len()
            );
        } else {
            assert!(square.is_empty(), "{}: {square:?}", e.name);
        }
    }
    for e in &corpus::representative() {
        let c = e.closed_reference();
        assert!(topology::creases(&c.mesh, 0.5).is_empty(), "{}", c.name);
    }
}

#[test]
fn the_fin_makes_one_non_manifold_edge() {
    for e in at_origin() {
        let edges = topology::non_manifold_edges(&e.mesh);
        assert_eq!(
            edges.len(),
            e.expect.non_manifold_edges,
            "{}: non-manifold edges {edges:?}",
            e.name
        );
        let faces = topology::edge_faces(&e.mesh);
        for edge in edges {
            assert_eq!(faces[&edge].len(), 3, "{}: faces on {edge:?}", e.name);
        }
    }
}

/// The brow's collapsed ends leave zero-area triangles that pelage calls
/// degenerate, and slivers beside them; the pole fans and the zipped
/// meridians leave more slivers.
#[test]
fn zero_area_triangles_and_slivers_exist() {
    for e in at_origin() {
        let zero = topology::zero_area_faces(&e.mesh);
        let degenerate = topology::degenerate_faces(&e.mesh);
        let worst = (0..e.mesh.triangle_count())
            .filter(|f| degenerate.binary_search(f).is_err())
            .map(|f| topology::aspect(&e.mesh, f))
            .fold(0.0, f64::max);
        println!(
            "{}: {} zero-area, {} degenerate, worst aspect of the others {worst:.0}",
            e.name,
            zero.len(),
            degenerate.len()
        );
        assert!(
            zero.len() >= e.expect.zero_area_faces,
            "{}: zero-area faces {zero:?}",
            e.name
        );
        assert!(
            zero.iter().all(|f| degenerate.binary_search(f).is_ok()),
            "{}: a zero-area face pelage does not call degenerate",
            e.name
        );
        if is_corpus_head(e) {
            assert_eq!(zero.len(), 4, "{}: zero-area faces {zero:?}", e.name);
            assert!(worst > 100.0, "{}: worst aspect {worst}", e.name);
        }
    }
}

/// The ears are thinner than r_hex of 10K roots on the whole mesh: the two
/// sides of a thin part closer than the hair spacing.
#[test]
fn the_ears_are_thinner_than_the_hair_spacing() {
    for e in at_origin() {
        let Some((name, thin)) = e.expect.thin else {
            continue;
        };
        let spacing = r_hex(topology::area(&e.mesh), 10_000) as f64;
        for faces in e.part_faces(name) {
            let t = topology::thickness(&topology::part_points(&e.mesh, faces.clone()));
            println!(
                "{}: {name} {faces:?} {t:.5} thick, r_hex {spacing:.5}",
                e.name
            );
            assert!(t <= thin * 1.001, "{}: {name} is {t} thick", e.name);
            assert!(t < 0.5 * spacing, "{}: {name} {t}, r_hex {spacing}", e.name);
        }
    }
}

/// A mesh without UVs gives the C API a NULL UV pointer; its faces are
/// those of the same mesh with UVs.
#[test]
fn meshes_without_uvs_pass_null_uvs() {
    for e in all() {
        let d = e.desc();
        assert_eq!(d.uvs.is_null(), !e.has_uvs(), "{}", e.name);
        assert_eq!(d.normals.is_null(), !e.recipe.normals, "{}", e.name);
        assert_eq!(e.view().uvs.is_some(), e.has_uvs(), "{}", e.name);
        if !e.has_uvs() {
            let with = CorpusMesh::new(
                "with",
                "",
                corpus::Recipe {
                    uvs: true,
                    ..e.recipe
                },
            );
            assert_eq!(with.mesh.positions, e.mesh.positions, "{}", e.name);
            assert_eq!(with.mesh.triangles, e.mesh.triangles, "{}", e.name);
        }
        let mesh = e.view();
        let report = mesh.validate().expect("a valid mesh");
        assert!(
            report.degenerate_triangles >= e.expect.zero_area_faces,
            "{}: {report:?}",
            e.name
        );
    }
}

/// Each placed mesh is its mesh at the origin rotated and moved: the same
/// triangles and UVs, and every point where the rigid motion takes it, to
/// within one float32 rounding of the result.
#[test]
fn placed_meshes_are_the_same_mesh_moved() {
    let mut placed = 0;
    for e in all().iter().filter(|e| e.recipe.is_placed()) {
        placed += 1;
        let base = e.at_origin();
        let (m, b) = (&e.mesh, &base.mesh);
        assert_eq!(m.triangles, b.triangles, "{}", e.name);
        assert_eq!(m.uvs, b.uvs, "{}", e.name);
        let r = e.recipe;
        let mut worst = 0.0f64;
        for (p, q) in m.positions.iter().zip(&b.positions) {
            let moved = r.rotation * DVec3::from(q.map(f64::from)) + r.offset;
            let p = DVec3::from(p.map(f64::from));
            // half an ulp per coordinate, of the largest coordinate
            let ulp = f64::from(f32::EPSILON) * p.abs().max_element();
            let err = (p - moved).abs().max_element() / ulp;
            worst = worst.max(err);
        }
        println!("{}: worst rounding {worst:.3} ulp", e.name);
        assert!(
            worst <= 0.5 + 1e-9,
            "{}: a point is {worst} ulp off",
            e.name
        );
        for (n, k) in m.normals.iter().zip(&b.normals) {
            let turned = r.rotation * DVec3::from(k.map(f64::from));
            let n = DVec3::from(n.map(f64::from));
            assert!(n.distance(turned) < 1e-6, "{}: normal {n} {turned}", e.name);
        }
        // as far from the origin as promised
        let (lo, hi) = m.bounds();
        let (lo, hi) = (Vec3::from(lo).as_dvec3(), Vec3::from(hi).as_dvec3());
        let (d, want) = (((lo + hi) / 2.0).length(), r.offset.length());
        assert!((d - want).abs() < (hi - lo).length(), "{}: {d}", e.name);
    }
    assert!(placed >= 8, "{placed} placed meshes");
}

/// Each mesh's closed reference is one closed, outward shell (at the
/// origin: far away, rounding may weld its pole's vertices) with its size,
/// triangle count, UVs and placement.
#[test]
fn closed_references_are_closed_single_shells_like_their_mesh() {
    for e in all() {
        let c = e.closed_reference();
        if !c.recipe.is_placed() {
            let b = topology::boundary(&c.mesh);
            let (_, shells) = topology::shells(&c.mesh);
            assert_eq!(
                (b.loops.len(), b.chains, b.pinched, shells),
                (0, 0, 0, 1),
                "{}: boundary and shells",
                c.name
            );
            assert!(
                topology::non_manifold_edges(&c.mesh).is_empty(),
                "{}",
                c.name
            );
            assert!(topology::degenerate_faces(&c.mesh).is_empty(), "{}", c.name);
        }
        let (n, k) = (
            e.mesh.triangle_count() as f64,
            c.mesh.triangle_count() as f64,
        );
        assert!(
            (k / n - 1.0).abs() < 0.05,
            "{}: {k} triangles for {n}",
            c.name
        );
        assert_eq!(c.has_uvs(), e.has_uvs(), "{}", c.name);
        assert_eq!(c.mesh.normals.is_empty(), e.mesh.normals.is_empty());
        let size = |m: &pelage_tests::creature::CreatureMesh| {
            let (lo, hi) = m.bounds();
            let (lo, hi) = (Vec3::from(lo).as_dvec3(), Vec3::from(hi).as_dvec3());
            ((lo + hi) / 2.0, (hi - lo).length())
        };
        let ((ce, de), (cc, dc)) = (size(&e.mesh), size(&c.mesh));
        assert!(
            (dc / de - 1.0).abs() < 0.3,
            "{}: size {dc} for {de}",
            c.name
        );
        assert!(
            ce.distance(cc) < 0.25 * de,
            "{}: centre {cc} for {ce}",
            c.name
        );
        // outward: positive volume, measured about the centre
        let volume: f64 = c
            .mesh
            .triangles
            .iter()
            .map(|t| {
                let [a, b, d] = t.map(|i| point(&c, i) - cc);
                a.dot(b.cross(d)) / 6.0
            })
            .sum();
        assert!(volume > 0.02 * dc.powi(3), "{}: volume {volume}", c.name);
    }
}

#[test]
fn the_corpus_is_deterministic() {
    for (a, b) in corpus::representative().iter().zip(&all()[..4]) {
        assert_eq!(a.mesh, b.mesh, "{}", a.name);
        assert_eq!(a.parts, b.parts, "{}", a.name);
    }
}

const TARGET: u32 = 20_000;

/// On every representative mesh the stamp writes about the target count of
/// roots, each on a triangle that is not degenerate with valid barycentric
/// coordinates (so on the surface), finite, with ids and ranks that are
/// permutations, the same bits on a second call, and the same roots with
/// and without UVs.
#[test]
fn the_stamp_puts_roots_on_every_representative_mesh() {
    let mut by_faces: HashMap<Vec<[u32; 3]>, Vec<Root>> = HashMap::new();
    for e in &corpus::representative() {
        let (roots, info, time) = e.stamp(TARGET, 1);
        println!("{}: {} roots in {time:.2?}, {info:?}", e.name, roots.len());
        let n = roots.len();
        assert!(
            n.abs_diff(TARGET as usize) * 100 <= TARGET as usize,
            "{}: {n} roots for {TARGET}",
            e.name
        );
        assert!(
            info.degenerate_triangles as usize >= e.expect.zero_area_faces,
            "{}: {info:?}",
            e.name
        );
        let mesh = e.view();
        let (mut ids, mut ranks) = (vec![false; n], vec![false; n]);
        for r in &roots {
            let f = r.face as usize;
            assert!(f < e.mesh.triangle_count(), "{}: {r:?}", e.name);
            assert!(
                !mesh.is_degenerate(f),
                "{}: a root on a degenerate face",
                e.name
            );
            assert!(
                r.u.is_finite() && r.v.is_finite() && r.u >= 0.0 && r.v >= 0.0,
                "{}: {r:?}",
                e.name
            );
            assert!(r.u + r.v <= 1.0 + 1e-6, "{}: {r:?}", e.name);
            assert!(mesh.point(f, r.u, r.v).is_finite(), "{}: {r:?}", e.name);
            assert!(
                (r.id as usize) < n && !std::mem::replace(&mut ids[r.id as usize], true),
                "{}: id {}",
                e.name,
                r.id
            );
            assert!(
                (r.rank as usize) < n && !std::mem::replace(&mut ranks[r.rank as usize], true),
                "{}: rank {}",
                e.name,
                r.rank
            );
        }
        // fur on the head shell and on the ears, which stand out of it
        for part in ["head", "ear"] {
            for faces in e.part_faces(part) {
                let on = roots.iter().filter(|r| faces.contains(&(r.face as usize)));
                assert!(on.count() > 0, "{}: no root on {part} {faces:?}", e.name);
            }
        }
        let (again, _, _) = e.stamp(TARGET, 1);
        assert!(again == roots, "{}: a second stamp differs", e.name);
        // UVs do not move a root (the same faces, no density map)
        if !e.recipe.is_placed() {
            if let Some(other) = by_faces.insert(e.mesh.triangles.clone(), roots.clone()) {
                assert!(other == roots, "{}: roots depend on UVs", e.name);
            }
        }
    }
}

/// Far from the origin the fur covers the skin as it does at the origin:
/// the roots of a placed mesh, measured on its twin at the origin (the
/// same faces and barycentric coordinates), leave no more empty space and
/// give each part as many roots. The stamp's buried test lifted a point a
/// thousandth of a disk radius off the skin, which rounds away there: a
/// metre-scale head at 1e3 had 1 root on its crown for 1,335.
#[test]
fn far_from_the_origin_the_fur_covers_as_at_the_origin() {
    let placed: Vec<CorpusMesh> = corpus::representative()
        .into_iter()
        .filter(|e| e.recipe.is_placed())
        .collect();
    assert!(!placed.is_empty(), "the subset holds a placed mesh");
    for e in &placed {
        let origin = e.at_origin();
        let mesh = origin.view();
        let shells = origin.shells();
        let mut memory = vec![0u8; Body::required_bytes(&mesh).expect("body size")];
        let body = Body::new(&mesh, &mut Arena::new(&mut memory)).expect("body");
        let skin = Skin::unburied(mesh, &shells, |_| true, &body);
        let cover = |roots: &[Root]| {
            let es = empty_space(&skin, roots, 16, 7);
            let head = e.part_faces("head");
            let on_head = roots
                .iter()
                .filter(|r| head.iter().any(|f| f.contains(&(r.face as usize))))
                .count();
            (es.p999, es.max, on_head)
        };
        let (far, _, _) = e.stamp(TARGET, 1);
        let (near, _, _) = origin.stamp(TARGET, 1);
        let (far_p999, far_max, far_head) = cover(&far);
        let (p999, max, head) = cover(&near);
        println!(
            "{}: empty p99.9 {far_p999:.3} (origin {p999:.3}), max {far_max:.3} ({max:.3}), \
             {far_head} roots on the head ({head})",
            e.name
        );
        assert!(
            far_p999 <= p999 + 0.02,
            "{}: empty p99.9 {far_p999} vs {p999}",
            e.name
        );
        // the single widest gap moves with the roots: a looser bound
        assert!(
            far_max <= max + 0.1,
            "{}: empty max {far_max} vs {max}",
            e.name
        );
        assert!(
            far_head.abs_diff(head) * 50 <= head,
            "{}: {far_head} roots on the head, {head} at the origin",
            e.name
        );
    }
}

/// Roots that face the same open air keep the disk radius at creases
/// too: no such pair closer than 0.70 r_hex in the whole stamp, nor than
/// 0.5 of their own r_hex in its 50% and 25% rank prefixes (the floor
/// the prefixes keep on flat skin, issue 30). The stamp's
/// same-side rule read a 90 degree crease (normals' dot about 0) as two
/// sides of a thin part: 55 pairs under 0.5 r_hex on the coarse head, down
/// to 0.054. Far from the origin the faces' planes round (a 1e3 placement
/// of a 0.25 head: 2 pairs at 0.58), which the local origin of issue 48 is
/// to take away; those meshes are held to 0.5.
#[test]
fn roots_facing_the_same_air_keep_their_distance_at_creases() {
    for e in &corpus::representative() {
        let (roots, _, _) = e.stamp(TARGET, 1);
        let origin = e.at_origin();
        let mesh = origin.view();
        let far = e.recipe.is_placed();
        let shells = origin.shells();
        let mut memory = vec![0u8; Body::required_bytes(&mesh).expect("body size")];
        let body = Body::new(&mesh, &mut Arena::new(&mut memory)).expect("body");
        // r_hex over the skin that grows fur, as the stamp spaces it
        let skin = Skin::unburied(mesh, &shells, |_| true, &body);
        for fraction in [1.0, 0.5, 0.25] {
            let bound = if far || fraction < 1.0 { 0.5 } else { 0.70 };
            let n = (roots.len() as f64 * fraction) as usize;
            let prefix: Vec<Root> = roots
                .iter()
                .copied()
                .filter(|r| (r.rank as usize) < n)
                .collect();
            let rh = skin.r_hex(prefix.len());
            let (air, _) = same_air_pairs(&mesh, &prefix, bound * rh);
            let closest = air.iter().fold(f32::INFINITY, |a, &b| a.min(b)) / rh;
            println!(
                "{} {fraction}: {} same-air pairs under {bound} r_hex (closest {closest:.3})",
                e.name,
                air.len()
            );
            assert!(
                air.is_empty(),
                "{} {fraction}: {} pairs, closest {closest} r_hex",
                e.name,
                air.len()
            );
        }
    }
}
