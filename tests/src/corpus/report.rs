//! The stamp's figures on the corpus, a row per mesh and the worst, for
//! the `stamp_corpus` bench (`make perf` writes them to
//! docs/PERFORMANCE.md) and the corpus tests.

use std::collections::HashMap;
use std::time::Duration;

use glam::Vec3;
use pelage_core::surface::body::Body;
use pelage_core::{Arena, Root};

use super::{topology, CorpusMesh};
use crate::quality::{empty_space, neighbours, Skin};

/// Roots each stamp of the table aims at.
pub const TARGET: u32 = 20_000;

/// Root pairs closer than `limit` (a distance) that face the same open
/// air: each root lies in front of the other's face (not behind its
/// tangent plane), so neither is hidden from the other by the skin. Returns
/// the pairs' distances, and those of the pairs across a crease (faces'
/// normals' dot product at most 0.1), which the stamp's same-side rule
/// does not space.
pub fn same_air_pairs(
    mesh: &pelage_core::Mesh,
    roots: &[Root],
    limit: f32,
) -> (Vec<f32>, Vec<f32>) {
    let pts: Vec<(Vec3, Vec3)> = roots
        .iter()
        .map(|r| {
            let f = r.face as usize;
            (mesh.point(f, r.u, r.v), mesh.face_normal(f))
        })
        .collect();
    let cell = |p: Vec3| (p / limit).floor().as_ivec3();
    let mut grid: HashMap<glam::IVec3, Vec<usize>> = HashMap::new();
    for (i, p) in pts.iter().enumerate() {
        grid.entry(cell(p.0)).or_default().push(i);
    }
    let (mut all, mut crease) = (Vec::new(), Vec::new());
    for (i, &(p, n)) in pts.iter().enumerate() {
        let c = cell(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(near) = grid.get(&(c + glam::IVec3::new(dx, dy, dz))) else {
                        continue;
                    };
                    for &j in near.iter().filter(|&&j| j > i) {
                        let (q, m) = pts[j];
                        let d = p.distance(q);
                        if d < limit && (q - p).dot(n) >= 0.0 && (p - q).dot(m) >= 0.0 {
                            all.push(d);
                            if n.dot(m) <= 0.1 {
                                crease.push(d);
                            }
                        }
                    }
                }
            }
        }
    }
    (all, crease)
}

pub fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

/// One mesh's figures (see [`stamp_table`]).
#[derive(Clone, Debug, Default)]
pub struct Row {
    name: String,
    triangles: usize,
    roots: usize,
    stamp_ms: f64,
    closed_ms: f64,
    radius: f32,
    nn_min: f32,
    nn_mean: f32,
    air_half: usize,
    air_07: usize,
    air_min: f32,
    crease_07: usize,
    crease_min: f32,
    empty_p999: f32,
    empty_max: f32,
    per_part: Vec<usize>,
    /// For a placed mesh: roots with no root of the origin stamp within
    /// 0.01 r_hex, and the largest distance to the nearest one (r_hex).
    moved: Option<(usize, f32)>,
    /// Distinct vertex positions that rounding merged.
    welded: usize,
}

impl Row {
    fn print(&self) {
        let moved = self
            .moved
            .map_or("- | -".to_string(), |(n, d)| format!("{n} | {d:.3}"));
        println!(
            "| {} | {} | {} | {:.1} | {:.1} | {:.2} | {:.3} | {:.3} | {:.3} | {} | {} | {:.3} | {} | {:.3} | {:.3} | {:.3} | {:?} | {moved} | {} |",
            self.name,
            self.triangles,
            self.roots,
            self.stamp_ms,
            self.closed_ms,
            self.stamp_ms / self.closed_ms,
            self.radius,
            self.nn_min,
            self.nn_mean,
            self.air_half,
            self.air_07,
            self.air_min,
            self.crease_07,
            self.crease_min,
            self.empty_p999,
            self.empty_max,
            self.per_part,
            self.welded,
        );
    }
}

/// The baseline row of `e`. The roots are stamped on `e`, where it is;
/// every distance is measured on its twin at the origin (the same faces
/// and barycentric coordinates, in f32 at the origin), so a placed mesh's
/// figures are not blurred by the rounding of the measure itself.
pub fn baseline_row(e: &CorpusMesh) -> Row {
    let time = |e: &CorpusMesh| median((0..3).map(|_| e.stamp(TARGET, 1).2).collect());
    let (roots, info, _) = e.stamp(TARGET, 1);
    let origin = e.at_origin();
    let mesh = origin.view();
    let shells = origin.shells();
    let mut memory = vec![0u8; Body::required_bytes(&mesh).expect("body size")];
    let body = Body::new(&mesh, &mut Arena::new(&mut memory)).expect("body");
    let skin = Skin::unburied(mesh, &shells, |_| true, &body);
    let rh = skin.r_hex(roots.len());
    let nn = neighbours(&skin, &roots, 0.0);
    let (air, crease) = same_air_pairs(&mesh, &roots, 0.7 * rh);
    let below = |v: &[f32], k: f32| v.iter().filter(|&&d| d < k * rh).count();
    let min = |v: &[f32]| v.iter().fold(f32::INFINITY, |a, &b| a.min(b)) / rh;
    let es = empty_space(&skin, &roots, 16, 7);
    let per_part = ["head", "eye", "tooth", "ear"]
        .iter()
        .map(|p| {
            let parts = e.part_faces(p);
            roots
                .iter()
                .filter(|r| parts.iter().any(|f| f.contains(&(r.face as usize))))
                .count()
        })
        .collect();
    let moved = e.recipe.is_placed().then(|| {
        let (base, _, _) = origin.stamp(TARGET, 1);
        let far: Vec<Vec3> = roots
            .iter()
            .map(|r| mesh.point(r.face as usize, r.u, r.v))
            .collect();
        let near: Vec<Vec3> = base
            .iter()
            .map(|r| mesh.point(r.face as usize, r.u, r.v))
            .collect();
        let d = nearest_distances(&far, &near, rh);
        let moved = d.iter().filter(|&&x| x > 0.01).count();
        (moved, d.iter().fold(0.0f32, |a, &b| a.max(b)))
    });
    let welded = {
        let distinct = |w: Vec<u32>| {
            w.iter()
                .enumerate()
                .filter(|&(i, &k)| i == k as usize)
                .count()
        };
        distinct(topology::welded(&origin.mesh)) - distinct(topology::welded(&e.mesh))
    };
    Row {
        name: e.name.clone(),
        triangles: e.mesh.triangle_count(),
        roots: roots.len(),
        stamp_ms: time(e).as_secs_f64() * 1e3,
        closed_ms: time(&e.closed_reference()).as_secs_f64() * 1e3,
        radius: info.radius / rh,
        nn_min: nn.min,
        nn_mean: nn.mean,
        air_half: below(&air, 0.5),
        air_07: air.len(),
        air_min: min(&air),
        crease_07: crease.len(),
        crease_min: min(&crease),
        empty_p999: es.p999,
        empty_max: es.max,
        per_part,
        moved,
        welded,
    }
}

/// For each point of `a`, the distance to the nearest point of `b`, in
/// units of `unit` (searched within 4 units; farther counts as 4).
pub fn nearest_distances(a: &[Vec3], b: &[Vec3], unit: f32) -> Vec<f32> {
    let cell = |p: Vec3| (p / unit).floor().as_ivec3();
    let mut grid: HashMap<glam::IVec3, Vec<usize>> = HashMap::new();
    for (i, p) in b.iter().enumerate() {
        grid.entry(cell(*p)).or_default().push(i);
    }
    a.iter()
        .map(|p| {
            let c = cell(*p);
            let mut best = 4.0 * unit;
            for dx in -4..=4 {
                for dy in -4..=4 {
                    for dz in -4..=4 {
                        if let Some(near) = grid.get(&(c + glam::IVec3::new(dx, dy, dz))) {
                            for &j in near {
                                best = best.min(p.distance(b[j]));
                            }
                        }
                    }
                }
            }
            best / unit
        })
        .collect()
}

/// Prints the stamp's figures over `list`, at 20K roots, one row per mesh, each
/// placed mesh preceded by its twin at the origin, then the worst of each
/// column:
/// - the stamp's time (median of 3), the closed reference's, their ratio;
/// - the stamp's radius, and the nearest same-side neighbours' minimum and
///   mean, in units of r_hex;
/// - root pairs that face the same air (each in front of the other's
///   face) closer than 0.5 and than 0.7 r_hex, and the closest, in r_hex;
///   then those across a crease (normals' dot at most 0.1) closer than 0.7
///   and the closest;
/// - empty space over the skin the stamp's rule calls unburied (the body
///   with capped holes): 99.9th percentile and maximum, in r_hex;
/// - roots on the head shell, eyes, teeth and ears;
/// - for a placed mesh: roots with no root of its twin's stamp within 0.01
///   r_hex, and the largest distance to the nearest (4 stands for 4 or
///   more); distinct vertex positions that rounding merged.
pub fn stamp_table(list: Vec<CorpusMesh>) {
    let mut meshes: Vec<CorpusMesh> = Vec::new();
    for e in list {
        let twin = e.recipe.at_origin();
        if e.recipe.is_placed() && !meshes.iter().any(|m| m.recipe == twin) {
            meshes.push(e.at_origin());
        }
        meshes.push(e);
    }
    println!(
        "| mesh | tris | roots | stamp ms | closed ms | ratio | radius | NN min | NN mean \
         | same air <0.5 | <0.7 | min | across creases <0.7 | min | empty p99.9 | max \
         | roots head/eye/tooth/ear | moved vs origin | max | welded |"
    );
    println!("|{}", "---|".repeat(20));
    let rows: Vec<Row> = meshes.iter().map(baseline_row).collect();
    let mut worst = Row {
        name: "worst".into(),
        radius: f32::INFINITY,
        nn_min: f32::INFINITY,
        nn_mean: f32::INFINITY,
        air_min: f32::INFINITY,
        crease_min: f32::INFINITY,
        closed_ms: f64::INFINITY,
        ..Row::default()
    };
    for r in &rows {
        r.print();
        worst.triangles = worst.triangles.max(r.triangles);
        worst.roots = worst.roots.max(r.roots);
        if r.stamp_ms / r.closed_ms > worst.stamp_ms / worst.closed_ms {
            (worst.stamp_ms, worst.closed_ms) = (r.stamp_ms, r.closed_ms);
        }
        worst.radius = worst.radius.min(r.radius);
        worst.nn_min = worst.nn_min.min(r.nn_min);
        worst.nn_mean = worst.nn_mean.min(r.nn_mean);
        worst.air_half = worst.air_half.max(r.air_half);
        worst.air_07 = worst.air_07.max(r.air_07);
        worst.air_min = worst.air_min.min(r.air_min);
        worst.crease_07 = worst.crease_07.max(r.crease_07);
        worst.crease_min = worst.crease_min.min(r.crease_min);
        worst.empty_p999 = worst.empty_p999.max(r.empty_p999);
        worst.empty_max = worst.empty_max.max(r.empty_max);
        worst.welded = worst.welded.max(r.welded);
        if let Some((n, d)) = r.moved {
            let (wn, wd) = worst.moved.unwrap_or((0, 0.0));
            worst.moved = Some((wn.max(n), wd.max(d)));
        }
    }
    // the worst row's times are those of the worst ratio
    worst.print();
}
