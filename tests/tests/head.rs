//! The head test mesh has what it promises: valid numbers and indices,
//! closed and outward parts, a head shell with exactly its open loops,
//! very uneven triangles, and parts that cut through the head shell.

use std::collections::HashMap;
use std::ops::Range;
use std::sync::OnceLock;

use glam::DVec3;
use pelage_tests::creature::CreatureMesh;
use pelage_tests::head::{head, head_with_parts, skull_radius, HeadParts, HEAD_BOUNDARY_LOOPS};

fn mesh() -> &'static (CreatureMesh, HeadParts) {
    static M: OnceLock<(CreatureMesh, HeadParts)> = OnceLock::new();
    M.get_or_init(head_with_parts)
}

fn point(m: &CreatureMesh, i: u32) -> DVec3 {
    DVec3::from(m.positions[i as usize].map(f64::from))
}

/// Directed edge uses of the faces in `faces`, with vertices welded by
/// bit-identical position (seam duplicates are one vertex).
fn directed_edges(m: &CreatureMesh, faces: Range<usize>) -> HashMap<(u32, u32), u32> {
    let mut ids = HashMap::new();
    let mut weld = |i: u32| -> u32 {
        let n = ids.len() as u32;
        *ids.entry(m.positions[i as usize].map(f32::to_bits))
            .or_insert(n)
    };
    let mut edges = HashMap::new();
    for t in &m.triangles[faces] {
        let v = t.map(&mut weld);
        assert!(v[0] != v[1] && v[1] != v[2] && v[2] != v[0], "{t:?}");
        for k in 0..3 {
            *edges.entry((v[k], v[(k + 1) % 3])).or_default() += 1;
        }
    }
    edges
}

/// Six times the signed volume enclosed by `faces`, seen from the origin.
fn signed_volume(m: &CreatureMesh, faces: Range<usize>) -> f64 {
    m.triangles[faces]
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| point(m, i));
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

#[test]
fn numbers_and_indices_are_valid() {
    let (m, parts) = mesh();
    let n = m.triangle_count();
    println!("{} vertices, {n} triangles, {parts:?}", m.vertex_count());
    // the counts the module docs give
    assert_eq!((m.vertex_count(), n), (42_957, 85_440));
    assert_eq!(parts.head.len(), 59_072);
    assert_eq!(
        parts.closed().map(|p| p.len()),
        [5120, 5120, 3840, 6144, 6144]
    );
    assert_eq!(m.uvs.len(), m.vertex_count());
    assert_eq!(m.normals.len(), m.vertex_count());
    assert!(m.positions.iter().flatten().all(|x| x.is_finite()));
    for uv in &m.uvs {
        assert!(uv.iter().all(|x| (0.0..=1.0).contains(x)), "{uv:?}");
    }
    for nrm in &m.normals {
        let l = DVec3::from(nrm.map(f64::from)).length();
        assert!((l - 1.0).abs() < 1e-5, "normal length {l}");
    }
    let nv = m.vertex_count() as u32;
    assert!(m.triangles.iter().flatten().all(|&i| i < nv));
    // every vertex is used
    let mut used = vec![false; m.vertex_count()];
    m.triangles
        .iter()
        .flatten()
        .for_each(|&i| used[i as usize] = true);
    assert!(used.iter().all(|&u| u));
    // the parts cover the faces in order
    let shells = parts.shells();
    assert_eq!(shells.len(), n);
    assert_eq!(parts.head.start, 0);
    let mut end = parts.head.end;
    for p in parts.closed() {
        assert_eq!(p.start, end);
        assert!(!p.is_empty());
        end = p.end;
    }
    assert_eq!(end, n);
    assert_eq!(shells[parts.horn.start], 3);
    assert_eq!(shells[n - 1], 5);
}

#[test]
fn deterministic() {
    assert_eq!(head(), mesh().0);
}

#[test]
fn closed_parts_are_closed_and_outward() {
    let (m, parts) = mesh();
    for part in parts.closed() {
        let edges = directed_edges(m, part.clone());
        for (&(a, b), &c) in &edges {
            assert_eq!(c, 1, "{part:?}: edge ({a}, {b}) used {c} times one way");
            assert_eq!(
                edges.get(&(b, a)),
                Some(&1),
                "{part:?}: edge ({a}, {b}) has no opposite"
            );
        }
        // the volume does not depend on the origin for a closed shell
        let v = signed_volume(m, part.clone());
        assert!(v > 0.0, "{part:?}: signed volume {v}");
        println!("{part:?}: {} triangles, volume {v:.5}", part.len());
    }
}

#[test]
fn head_shell_has_its_open_loops_and_is_oriented() {
    let (m, parts) = mesh();
    let edges = directed_edges(m, parts.head.clone());
    let mut next = HashMap::new();
    for (&(a, b), &c) in &edges {
        assert_eq!(c, 1, "edge ({a}, {b}) used {c} times one way");
        if !edges.contains_key(&(b, a)) {
            // boundary edge: the loops must be simple, one way out of each
            assert!(next.insert(a, b).is_none(), "vertex {a} pinches two loops");
        }
    }
    let mut loops = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for &start in next.keys() {
        if seen.contains(&start) {
            continue;
        }
        let (mut v, mut len) = (start, 0);
        while seen.insert(v) {
            v = next[&v];
            len += 1;
        }
        assert_eq!(v, start, "boundary is not a loop");
        loops.push(len);
    }
    loops.sort();
    println!("head boundary loops (edges): {loops:?}");
    assert_eq!(loops.len(), HEAD_BOUNDARY_LOOPS);
    let v = signed_volume(m, parts.head.clone());
    assert!(v > 0.3, "head shell signed volume {v}");
    // outward: every face's normal leaves the origin it is star-shaped around
    for t in &m.triangles[parts.head.clone()] {
        let [a, b, c] = t.map(|i| point(m, i));
        assert!((b - a).cross(c - a).dot(a + b + c) > 0.0, "{t:?}");
    }
}

#[test]
fn head_triangles_are_very_uneven() {
    let (m, parts) = mesh();
    let (mut lo, mut hi, mut aspect) = (f64::INFINITY, 0.0f64, 0.0f64);
    for t in &m.triangles[parts.head.clone()] {
        let [a, b, c] = t.map(|i| point(m, i));
        let area = 0.5 * (b - a).cross(c - a).length();
        let longest = (b - a).length().max((c - b).length()).max((a - c).length());
        lo = lo.min(area);
        hi = hi.max(area);
        // longest edge over the height onto it: 1.15 for an equilateral
        aspect = aspect.max(longest * longest / (2.0 * area));
    }
    println!(
        "head shell areas {lo:.3e} .. {hi:.3e} (x{:.0}), worst aspect {aspect:.0}",
        hi / lo
    );
    assert!(hi / lo > 1000.0);
    assert!(aspect > 100.0);
}

#[test]
fn parts_cut_through_the_head_shell() {
    let (m, parts) = mesh();
    for part in parts.closed() {
        let (mut inside, mut outside) = (0, 0);
        for t in &m.triangles[part.clone()] {
            for &i in t {
                let p = point(m, i);
                if p.length() < skull_radius(p.normalize()) {
                    inside += 1;
                } else {
                    outside += 1;
                }
            }
        }
        assert!(
            inside > 0 && outside > 0,
            "{part:?}: {inside} in, {outside} out"
        );
    }
}
