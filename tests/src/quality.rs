//! Stamp-quality measures (issue 30): empty space, same-side spacing with
//! pairs across shells, and the evenness of LOD prefixes, plus a
//! dart-throwing Poisson set to compare with.
//!
//! Every distance is in units of r_hex = sqrt(2A / (sqrt(3) N)), the spacing
//! of a perfect hexagonal lattice of the set's N points over the furred
//! area A, so 1.0 is the spacing no set of that count can beat everywhere.
//!
//! Distances are 3D, under the **same-side rule** the stamp promises its
//! spacing with: two points count for each other only when the normals of
//! their faces have a positive dot product, so the two sides of a thin ear
//! neither crowd nor cover each other.
//!
//! Searches run on grids with cells of two r_hex and visit the skin in a
//! spatially coherent order, so every measure is about linear in the count
//! and stays in cache (1M roots take seconds).

use glam::Vec3;
use pelage_core::rng::{self, Purpose};
use pelage_core::stamp::same_air;
use pelage_core::surface::body::Body;
use pelage_core::surface::grid::{floor_i32, HashGrid};
use pelage_core::{Mesh, Root};

use crate::measure::r_hex;

/// RNG counters of the surface samples of [`empty_space`] and of the darts
/// of [`dart_throwing`]: three each, clear of the counters
/// `measure::uniform_roots` uses (0 to 2), so no sample or dart lands on a
/// random root of the same seed.
const SAMPLE_COUNTERS: u32 = 3;
const DART_COUNTERS: u32 = 6;

/// A searched radius doubles at most this many times before the search
/// scans every point: only a point with no same-side neighbour within 32
/// times the first radius gets there.
const GROWTHS: u32 = 5;

/// Grid cells of the measures, in units of r_hex: a search within one r_hex
/// (the nearest neighbour of a good set) then reads about 2 cells a side.
const CELL: f32 = 2.0;
/// First radius of the empty-space search, in units of r_hex: most skin is
/// closer than this to a root of a good set.
const EMPTY_START: f32 = 0.7;

/// The surface measured: a mesh, the shell of each face, and the furred
/// faces (the only ones sampled and counted in the area).
pub struct Skin<'a> {
    mesh: Mesh<'a>,
    shells: &'a [u32],
    /// The body, when skin inside it (buried) grows no fur.
    body: Option<&'a Body<'a>>,
    /// Furred area of each face (0 for a bald or degenerate one).
    areas: Vec<f64>,
    /// Their sum (in f64: a million small faces add up without drift).
    area: f64,
    /// Walker's alias table over the faces by furred area: a face is drawn
    /// with one read, where a search of the running sums would miss the
    /// cache at every step.
    alias: Vec<(f32, u32)>,
}

impl<'a> Skin<'a> {
    /// The skin of `mesh`, whose face `f` belongs to shell `shells[f]` and
    /// grows fur when `furred(f)` (with a constant density, every face).
    /// Degenerate faces are never furred, as the stamp skips them.
    pub fn new(mesh: Mesh<'a>, shells: &'a [u32], furred: impl Fn(usize) -> bool) -> Self {
        Self::build(mesh, shells, furred, None)
    }

    /// [`Skin::new`], where the skin is furred only where it is not buried:
    /// where the point a thousandth of a radius outside it is not inside
    /// `body` with its holes capped (pelage's rule). The furred area counts
    /// each face's share that is not buried, from a grid of 36 points on it.
    pub fn unburied(
        mesh: Mesh<'a>,
        shells: &'a [u32],
        furred: impl Fn(usize) -> bool,
        body: &'a Body<'a>,
    ) -> Self {
        Self::build(mesh, shells, furred, Some(body))
    }

    fn build(
        mesh: Mesh<'a>,
        shells: &'a [u32],
        furred: impl Fn(usize) -> bool,
        body: Option<&'a Body<'a>>,
    ) -> Self {
        assert_eq!(shells.len(), mesh.triangle_count(), "one shell per face");
        const SIDE: usize = 8;
        let areas: Vec<f64> = (0..mesh.triangle_count())
            .map(|f| {
                if !furred(f) || mesh.is_degenerate(f) {
                    return 0.0;
                }
                let Some(body) = body else {
                    return mesh.area(f) as f64;
                };
                // the centres of a triangular grid of 36 sub-triangles
                let (mut open, mut all) = (0, 0);
                for i in 0..SIDE {
                    for j in 0..SIDE - i {
                        let (u, v) = (
                            (i as f32 + 1.0 / 3.0) / SIDE as f32,
                            (j as f32 + 1.0 / 3.0) / SIDE as f32,
                        );
                        all += 1;
                        open += !buried(body, &mesh, f, u, v, mesh.area(f).sqrt()) as usize;
                    }
                }
                mesh.area(f) as f64 * open as f64 / all as f64
            })
            .collect();
        let area = areas.iter().sum();
        Skin {
            mesh,
            shells,
            body,
            alias: alias_table(&areas, area),
            areas,
            area,
        }
    }

    /// The furred area.
    pub fn area(&self) -> f64 {
        self.area
    }

    /// r_hex of `n` points over the furred area.
    pub fn r_hex(&self, n: usize) -> f32 {
        r_hex(self.area, n)
    }

    /// Point `i` of a stream spread uniformly by furred area: its face and
    /// barycentric (u, v), from the RNG counters `counters..counters + 3`.
    fn sample(&self, seed: u64, i: u64, counters: u32) -> (usize, f32, f32) {
        let h = |c| rng::hash(seed, i, Purpose::Uniform, counters + c);
        // the low 32 bits pick the slot, the top 24 whether it keeps its face
        let slot = (((h(0) & 0xFFFF_FFFF) * self.alias.len() as u64) >> 32) as usize;
        let (keep, other) = self.alias[slot];
        let face = if rng::to_unit(h(0)) < keep {
            slot
        } else {
            other as usize
        };
        let (u, v) = fold(rng::to_unit(h(1)), rng::to_unit(h(2)));
        (face, u, v)
    }

    /// The point of a root, or of a sample, with its face's normal and shell.
    fn item(&self, face: usize, u: f32, v: f32, index: u32) -> Item {
        Item {
            pos: self.mesh.point(face, u, v),
            normal: self.mesh.face_normal(face),
            shell: self.shells[face],
            index,
        }
    }

    /// The items of `roots`, indexed by their place in `roots`.
    fn items(&self, roots: &[Root]) -> Vec<Item> {
        roots
            .iter()
            .enumerate()
            .map(|(i, r)| self.item(r.face as usize, r.u, r.v, i as u32))
            .collect()
    }
}

/// Walker's alias table (Vose's construction) for drawing faces in
/// proportion to `areas` (summing to `total`): slot i keeps face i with
/// the probability it holds, and otherwise gives its alias.
fn alias_table(areas: &[f64], total: f64) -> Vec<(f32, u32)> {
    let n = areas.len();
    let mut scaled: Vec<f64> = areas.iter().map(|a| a * n as f64 / total).collect();
    let mut table: Vec<(f32, u32)> = (0..n as u32).map(|i| (1.0, i)).collect();
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
    while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
        table[s] = (scaled[s] as f32, l as u32);
        scaled[l] -= 1.0 - scaled[s];
        if scaled[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // what rounding leaves in either list keeps its own face
    table
}

/// A uniform point of the unit square folded onto the triangle u + v <= 1.
fn fold(u: f32, v: f32) -> (f32, f32) {
    if u + v > 1.0 {
        (1.0 - u, 1.0 - v)
    } else {
        (u, v)
    }
}

/// A point of a set: where it is, the normal and shell of its face, and
/// its index in the set.
#[derive(Clone, Copy, Debug)]
struct Item {
    pos: Vec3,
    normal: Vec3,
    shell: u32,
    index: u32,
}

/// Hash of an integer cell: x enters linearly, so a row of cells along x
/// takes consecutive buckets and a query reads a row as one slice.
fn cell_hash(c: [i32; 3]) -> usize {
    (c[0] as u32)
        .wrapping_add((c[1] as u32).wrapping_mul(0x9E37_79B1))
        .wrapping_add((c[2] as u32).wrapping_mul(0x85EB_CA77)) as usize
}

/// A fixed set of points bucketed by cell, each bucket's points side by
/// side (sorted by bucket), so a query reads contiguous memory.
struct Grid {
    items: Vec<Item>,
    /// Where each bucket's points start in `items`, and one past the end.
    start: Vec<u32>,
    cell: f32,
}

impl Grid {
    fn new(items: Vec<Item>, cell: f32) -> Self {
        // two buckets per point, so few cells share one
        let buckets = (2 * items.len()).max(16).next_power_of_two();
        let mut grid = Grid {
            items: Vec::new(),
            start: vec![0; buckets + 1],
            cell,
        };
        let keys: Vec<usize> = items.iter().map(|it| grid.bucket(it.pos)).collect();
        for &k in &keys {
            grid.start[k + 1] += 1;
        }
        for b in 0..buckets {
            grid.start[b + 1] += grid.start[b];
        }
        let mut at = grid.start.clone();
        let mut sorted = items.clone();
        for (it, &k) in items.iter().zip(&keys) {
            sorted[at[k] as usize] = *it;
            at[k] += 1;
        }
        grid.items = sorted;
        grid
    }

    fn cell_of(&self, p: Vec3) -> [i32; 3] {
        let q = p / self.cell;
        [floor_i32(q.x), floor_i32(q.y), floor_i32(q.z)]
    }

    fn bucket(&self, p: Vec3) -> usize {
        cell_hash(self.cell_of(p)) & (self.start.len() - 2)
    }

    /// Calls `f` on every point in the cells overlapping the cube of
    /// half-side `r` around `p` (so every point within `r`; points of other
    /// cells sharing those buckets too, some perhaps twice), stopping at
    /// the first call that returns true; returns whether one did.
    #[inline]
    fn any(&self, p: Vec3, r: f32, mut f: impl FnMut(&Item) -> bool) -> bool {
        let (lo, hi) = (
            self.cell_of(p - Vec3::splat(r)),
            self.cell_of(p + Vec3::splat(r)),
        );
        let mask = self.start.len() - 2;
        // a row longer than the table reads the table once
        let row = ((hi[0] - lo[0]) as usize + 1).min(mask + 1);
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                let b = cell_hash([lo[0], y, z]) & mask;
                // a row that wraps past the last bucket is read in two
                let end = (b + row).min(mask + 1);
                let rest = b + row - end;
                for range in [b..end, 0..rest] {
                    let (s, e) = (self.start[range.start], self.start[range.end]);
                    if self.items[s as usize..e as usize].iter().any(&mut f) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// [`Grid::any`] without stopping.
    #[inline]
    fn visit(&self, p: Vec3, r: f32, mut f: impl FnMut(&Item)) {
        self.any(p, r, |it| {
            f(it);
            false
        });
    }

    /// Distance from `p` (on a face with normal `n`) to the nearest
    /// same-side point other than the one of index `skip`, searched first
    /// within `start`, then twice as far each time; infinite when there is
    /// none.
    fn nearest(&self, p: Vec3, n: Vec3, skip: u32, start: f32) -> f32 {
        let closest = |best: &mut f32, it: &Item| {
            if it.index != skip && same_air(p, n, it.pos, it.normal) {
                *best = best.min(p.distance_squared(it.pos));
            }
        };
        let mut r = start;
        for _ in 0..=GROWTHS {
            // only points within r are certain to be seen, so only a
            // nearest point within r is the nearest
            let mut best = r * r;
            self.visit(p, r, |it| closest(&mut best, it));
            if best < r * r {
                return best.sqrt();
            }
            r *= 2.0;
        }
        let mut best = f32::INFINITY;
        self.items.iter().for_each(|it| closest(&mut best, it));
        best.sqrt()
    }
}

/// Runs `f` over `0..n` split in one contiguous block per thread, and
/// returns the results in order (the same whatever the thread count).
fn par_map<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get());
    let block = n.div_ceil(threads).max(1);
    std::thread::scope(|s| {
        let f = &f;
        let parts: Vec<_> = (0..n)
            .step_by(block)
            .map(|start| s.spawn(move || (start..n.min(start + block)).map(f).collect::<Vec<T>>()))
            .collect();
        parts
            .into_iter()
            .flat_map(|h| h.join().expect("measure thread"))
            .collect()
    })
}

/// The `q` quantile of `v` (nearest rank), reordering `v`.
fn quantile(v: &mut [f32], q: f64) -> f32 {
    let k = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1;
    *v.select_nth_unstable_by(k, f32::total_cmp).1
}

/// How far the skin is from its nearest root: the distance from points
/// spread uniformly by area over the furred faces to the nearest
/// same-side root, in units of the roots' r_hex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmptySpace {
    /// 99th percentile.
    pub p99: f32,
    /// 99.9th percentile.
    pub p999: f32,
    /// Largest distance seen over the samples.
    pub max: f32,
    /// Where the largest distance was seen: the sample's face and point.
    pub worst: (usize, Vec3),
}

/// Faces per block of work of [`empty_space`]: enough blocks to share the
/// work evenly, each a run of neighbouring faces so its queries stay in
/// cache.
const FACES_PER_BLOCK: usize = 256;

/// [`EmptySpace`] of `roots` on `skin`, from about `samples_per_root`
/// samples per root drawn with `seed` (the same arguments give the same
/// answer). Each furred face takes its share of the samples by area
/// (rounded at random, so the count is right on average) placed uniformly
/// on it: uniform by area overall, and taken face by face, in mesh order.
pub fn empty_space(skin: &Skin, roots: &[Root], samples_per_root: usize, seed: u64) -> EmptySpace {
    let rh = skin.r_hex(roots.len());
    let grid = Grid::new(skin.items(roots), CELL * rh);
    let per_area = (samples_per_root * roots.len()) as f64 / skin.area();
    let faces = skin.areas.len();
    let blocks = par_map(faces.div_ceil(FACES_PER_BLOCK), |b| {
        let mut d = Vec::new();
        let mut worst = (0.0f32, 0, Vec3::ZERO);
        for face in b * FACES_PER_BLOCK..faces.min((b + 1) * FACES_PER_BLOCK) {
            let id = (face as u64) << 32;
            let h = |id, c| rng::hash(seed, id, Purpose::Uniform, SAMPLE_COUNTERS + c);
            let share = skin.areas[face] * per_area;
            let extra = (rng::to_unit(h(id, 2)) as f64) < share.fract();
            let normal = skin.mesh.face_normal(face);
            for j in 0..share as u64 + extra as u64 {
                let (u, v) = fold(rng::to_unit(h(id | j, 0)), rng::to_unit(h(id | j, 1)));
                let p = skin.mesh.point(face, u, v);
                if skin
                    .body
                    .is_some_and(|b| buried(b, &skin.mesh, face, u, v, rh))
                {
                    continue;
                }
                let dist = grid.nearest(p, normal, u32::MAX, EMPTY_START * rh) / rh;
                if dist > worst.0 {
                    worst = (dist, face, p);
                }
                d.push(dist);
            }
        }
        (d, worst)
    });
    let worst = blocks
        .iter()
        .map(|b| b.1)
        .fold((0.0, 0, Vec3::ZERO), |a, b| if b.0 > a.0 { b } else { a });
    let mut d: Vec<f32> = blocks.into_iter().flat_map(|b| b.0).collect();
    EmptySpace {
        p99: quantile(&mut d, 0.99),
        p999: quantile(&mut d, 0.999),
        max: worst.0,
        worst: (worst.1, worst.2),
    }
}

/// Whether the skin at `(u, v)` on `face` is buried: the point `scale /
/// 1000` outside it is inside `body` with its holes capped.
fn buried(body: &Body, mesh: &Mesh, face: usize, u: f32, v: f32, scale: f32) -> bool {
    let at = mesh.point(face, u, v);
    // as the stamp lifts: never by less than 16 float steps of the point
    let room = at.abs().max_element() * 16.0 * f32::EPSILON;
    let p = at + mesh.face_normal(face) * (1e-3 * scale).max(room);
    body.capped_winding(p) >= 1
}

/// Same-side nearest-neighbour statistics of a root set, in units of its
/// r_hex, and the pairs that break a promised spacing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbours {
    /// Smallest distance from a root to its nearest same-side root.
    pub min: f32,
    /// Mean of those distances.
    pub mean: f32,
    /// Their coefficient of variation (standard deviation over mean; 0 for
    /// a perfect lattice, about 0.52 for uniform random points).
    pub cv: f32,
    /// Same-side pairs closer than the radius asked for (each pair once).
    pub close_pairs: usize,
    /// Those of the close pairs whose roots lie on different shells.
    pub close_across_shells: usize,
}

/// [`Neighbours`] of `roots` on `skin`, counting pairs closer than `radius`
/// (a mesh distance, e.g. `StampReport::radius`). A pair within 1e-4 of
/// `radius` is not close: f32 barycentric points land that far off.
pub fn neighbours(skin: &Skin, roots: &[Root], radius: f32) -> Neighbours {
    let rh = skin.r_hex(roots.len());
    let grid = Grid::new(skin.items(roots), CELL * rh);
    let close = radius * (1.0 - 1e-4);
    // in the grid's order, neighbouring queries read the same memory
    let per_root = par_map(grid.items.len(), |k| {
        let it = grid.items[k];
        let nearest = grid.nearest(it.pos, it.normal, it.index, rh) / rh;
        // buckets that two cells share yield their points twice: a pair
        // must count once
        let mut near = Vec::new();
        grid.visit(it.pos, close, |o| {
            if o.index > it.index
                && same_air(it.pos, it.normal, o.pos, o.normal)
                && it.pos.distance(o.pos) < close
            {
                near.push((o.index, o.shell != it.shell));
            }
        });
        near.sort_unstable();
        near.dedup();
        let across = near.iter().filter(|o| o.1).count();
        (nearest, near.len(), across)
    });
    let n = per_root.len().max(1) as f64;
    let mean = per_root.iter().map(|r| r.0 as f64).sum::<f64>() / n;
    let var = per_root
        .iter()
        .map(|r| (r.0 as f64 - mean).powi(2))
        .sum::<f64>()
        / n;
    Neighbours {
        min: per_root.iter().map(|r| r.0).fold(f32::INFINITY, f32::min),
        mean: mean as f32,
        cv: (var.sqrt() / mean) as f32,
        close_pairs: per_root.iter().map(|r| r.1).sum(),
        close_across_shells: per_root.iter().map(|r| r.2).sum(),
    }
}

/// How even an LOD prefix is: the roots whose rank is below a fraction of
/// the count, measured in units of their own r_hex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prefix {
    /// Roots in the prefix.
    pub count: usize,
    /// Coefficient of variation of their same-side nearest-neighbour
    /// distances (among the prefix only).
    pub cv: f32,
    /// Their smallest same-side pair distance.
    pub min: f32,
}

/// [`Prefix`] of the roots of `roots` with rank below `fraction` times
/// their count.
pub fn prefix(skin: &Skin, roots: &[Root], fraction: f64) -> Prefix {
    let limit = (fraction * roots.len() as f64) as u32;
    let kept: Vec<Root> = roots.iter().copied().filter(|r| r.rank < limit).collect();
    // no pair is close at radius 0: only the distances are wanted
    let n = neighbours(skin, &kept, 0.0);
    Prefix {
        count: kept.len(),
        cv: n.cv,
        min: n.min,
    }
}

/// A dart-throwing Poisson set ([`dart_throwing`]) and its spacing.
pub struct Darts {
    /// The roots, ranked in the order they were accepted.
    pub roots: Vec<Root>,
    /// The spacing of the last phase: no two same-side roots are closer.
    pub radius: f32,
}

/// Darts thrown per root of a phase's count in each round of
/// [`dart_throwing`]; a round that ends short of the count shrinks the
/// spacing.
const DARTS_PER_ROOT: usize = 10;
/// First spacing of each phase, in units of its count's r_hex.
const DART_SPACING: f32 = 0.72;
/// Fewest darts drawn at a time (see [`dart_throwing`]).
const DART_BATCH: usize = 1 << 16;

/// The Poisson reference: `n` roots thrown as darts uniformly by furred
/// area (the stream of `seed`), each kept only if no kept same-side root is
/// within the spacing, in three phases that stop at n/4, n/2 and n roots.
/// Each phase starts at `DART_SPACING` times the r_hex of its count and
/// shrinks its spacing by 2% after every round of `DARTS_PER_ROOT` darts
/// per root of its count that ends short of the count; earlier roots keep
/// their larger spacing. So the set is close to maximal (few darts would
/// still find room), each rank prefix at 25% and 50% is a dart-throwing set
/// of its own size, and every same-side pair is at least [`Darts::radius`]
/// apart.
///
/// The outcome is that of throwing the darts one by one; for speed they
/// are drawn in batches at least as large as the set so far. A dart that a
/// root kept before its batch blocks fails whatever the batch does, so
/// that test runs first, in face order on a grid of those roots sorted by
/// cell (neighbouring tests read the same memory); only the darts that
/// pass, late in a phase a few, are then tested against each other in
/// their own order.
pub fn dart_throwing(skin: &Skin, n: usize, seed: u64) -> Darts {
    let mut kept: Vec<Item> = Vec::with_capacity(n);
    let mut roots = Vec::with_capacity(n);
    let mut heads = vec![0u32; HashGrid::buckets_for(n)];
    let mut next = vec![0u32; n];
    // the roots kept in the current batch
    let mut fresh = HashGrid::new(&mut heads, &mut next, 1.0);
    let mut dart = 0u64;
    let mut radius = 0.0;
    let blocks = |it: &Item, o: &Item, radius: f32| {
        same_air(it.pos, it.normal, o.pos, o.normal)
            && it.pos.distance_squared(o.pos) < radius * radius
    };
    for want in [n / 4, n / 2, n] {
        radius = DART_SPACING * skin.r_hex(want);
        let mut budget = DARTS_PER_ROOT * want;
        while roots.len() < want {
            if budget == 0 {
                radius *= 0.98;
                budget = DARTS_PER_ROOT * want;
            }
            // batches four times the set dwarf the cost of sorting the set
            let batch = budget.min(DART_BATCH.max(4 * kept.len()));
            budget -= batch;
            let before = Grid::new(kept.clone(), CELL * radius);
            let mut darts: Vec<(usize, f32, f32, u64)> = (dart..dart + batch as u64)
                .map(|i| {
                    let (face, u, v) = skin.sample(seed, i, DART_COUNTERS);
                    (face, u, v, i)
                })
                .collect();
            dart += batch as u64;
            darts.sort_unstable_by_key(|d| (d.0, d.3));
            let open = par_map(darts.len(), |k| {
                let it = skin.item(darts[k].0, darts[k].1, darts[k].2, 0);
                !before.any(it.pos, radius, |o| blocks(&it, o, radius))
            });
            let mut open: Vec<_> = darts
                .iter()
                .zip(open)
                .filter(|d| d.1)
                .map(|d| *d.0)
                .collect();
            open.sort_unstable_by_key(|d| d.3);
            let first = kept.len();
            fresh.reset(CELL * radius, open.len());
            for (face, u, v, _) in open {
                if roots.len() == want {
                    break;
                }
                let it = skin.item(face, u, v, roots.len() as u32);
                let taken = fresh.any_within(it.pos, radius, |j| {
                    blocks(&it, &kept[first + j as usize], radius)
                });
                if !taken {
                    fresh.insert(it.index - first as u32, it.pos);
                    kept.push(it);
                    roots.push(Root {
                        face: face as u32,
                        u,
                        v,
                        id: it.index,
                        rank: it.index,
                    });
                }
            }
        }
    }
    Darts { roots, radius }
}

/// The generalized winding number of `mesh` at `p` (the sum of its
/// triangles' signed solid angles over 4 pi, in f64 about `p`): 1 inside a
/// closed, outward-wound shell, 0 outside, and between across a hole. The
/// inside rule pelage's body evaluates (above 1/2 is inside), computed
/// here the slow, exact way as an oracle.
pub fn winding_number(mesh: &Mesh, p: Vec3) -> f64 {
    let p = p.as_dvec3();
    let mut total = 0.0;
    for f in 0..mesh.triangle_count() {
        let [a, b, c] = mesh.corners(f).map(|q| q.as_dvec3() - p);
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let numerator = a.dot(b.cross(c));
        let denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
        total += 2.0 * numerator.atan2(denominator);
    }
    total / (4.0 * std::f64::consts::PI)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::uniform_roots;
    use pelage_core::Strided;

    /// Lattice rows and columns: even, so each parity class holds a quarter.
    const M: usize = 60;

    /// A parallelogram of M x M hexagonal lattice cells of unit spacing
    /// (two triangles, normal +z), raised to height `z`.
    fn plane(z: f32) -> ([[f32; 3]; 4], [[u32; 3]; 2]) {
        let (e1, e2) = lattice_vectors();
        let m = M as f32;
        let c = [Vec3::ZERO, e1 * m, (e1 + e2) * m, e2 * m].map(|p| (p + Vec3::Z * z).into());
        (c, [[0, 1, 2], [0, 2, 3]])
    }

    fn lattice_vectors() -> (Vec3, Vec3) {
        (Vec3::X, Vec3::new(0.5, 3f32.sqrt() / 2.0, 0.0))
    }

    /// The lattice point at the centre of cell (a, b) of a plane, as a root
    /// on face `face_base` or the one after it. Ranks put (even, even)
    /// cells first, then (even, odd), then the rest.
    fn lattice_root(a: usize, b: usize, face_base: u32, id: u32) -> Root {
        let (s, t) = ((a as f32 + 0.5) / M as f32, (b as f32 + 0.5) / M as f32);
        // the parallelogram's corners are 0, e1 M, (e1 + e2) M, e2 M, so
        // the point s e1 M + t e2 M has these barycentrics on its half
        let (face, u, v) = if s >= t {
            (face_base, s - t, t)
        } else {
            (face_base + 1, s, t - s)
        };
        let class = match (a % 2, b % 2) {
            (0, 0) => 0,
            (0, _) => 1,
            _ => 2,
        };
        Root {
            face,
            u,
            v,
            id,
            rank: class << 24 | id,
        }
    }

    /// The lattice roots with their ranks made dense (0 to n - 1).
    fn lattice(face_base: u32) -> Vec<Root> {
        let mut roots: Vec<Root> = (0..M * M)
            .map(|i| lattice_root(i % M, i / M, face_base, i as u32))
            .collect();
        let mut order: Vec<usize> = (0..roots.len()).collect();
        order.sort_by_key(|&i| roots[i].rank);
        for (rank, i) in order.into_iter().enumerate() {
            roots[i].rank = rank as u32;
        }
        roots
    }

    fn close(a: f32, b: f32) -> bool {
        (a - b).abs() < 1e-3
    }

    #[test]
    fn a_hexagonal_lattice_is_perfectly_even() {
        let (pos, tris) = plane(0.0);
        let mesh = Mesh::new(Strided::from_slice(&pos), Strided::from_slice(&tris));
        let shells = [0; 2];
        let skin = Skin::new(mesh, &shells, |_| true);
        let roots = lattice(0);
        // the lattice's cells tile the plane, so its r_hex is its spacing
        assert!(close(skin.r_hex(roots.len()), 1.0));

        let n = neighbours(&skin, &roots, 0.99);
        assert!(
            close(n.min, 1.0) && close(n.mean, 1.0) && n.cv < 1e-3,
            "{n:?}"
        );
        assert_eq!((n.close_pairs, n.close_across_shells), (0, 0));
        // at a radius above the spacing every lattice edge is a close pair
        let edges = 3 * M * M - 2 * 2 * M + 1;
        assert_eq!(neighbours(&skin, &roots, 1.01).close_pairs, edges);

        // inside, no point is farther than the triangles' circumradius
        // 1/sqrt(3) from a lattice point; only the margin along the
        // border, a tiny part of the area, is farther (at most 1)
        let e = empty_space(&skin, &roots, 30, 1);
        assert!(e.p99 <= 0.578 && e.p99 > 0.5, "{e:?}");
        assert!(e.max <= 1.0 + 1e-3, "{e:?}");

        // the (even, odd) cells join the (even, even) ones in rows of
        // spacing 2 and their neighbours 1 away: half the count, each
        // point's neighbour at 1 = 1/sqrt(2) of its own r_hex
        let half = prefix(&skin, &roots, 0.5);
        assert_eq!(half.count, M * M / 2);
        assert!(close(half.min, 0.5f32.sqrt()) && half.cv < 1e-3, "{half:?}");
        // (even, even) cells are the lattice at twice the spacing
        let quarter = prefix(&skin, &roots, 0.25);
        assert_eq!(quarter.count, M * M / 4);
        assert!(close(quarter.min, 1.0) && quarter.cv < 1e-3, "{quarter:?}");

        // uniform random points are far less even
        let random = uniform_roots(&mesh, roots.len(), 3);
        let n = neighbours(&skin, &random, 0.99);
        assert!(n.min < 0.2 && n.cv > 0.4 && n.close_pairs > 500, "{n:?}");
        let e = empty_space(&skin, &random, 30, 1);
        assert!(e.p999 > 1.2 && e.max > e.p999, "{e:?}");
    }

    #[test]
    fn pairs_across_shells_and_sides() {
        // two lattice planes half a spacing apart, every point with a
        // partner on the other shell at 0.5 (twice the points on twice the
        // area: r_hex stays 1): facing the same way, or facing each other
        // across the gap, the pairs face the same air; facing away from
        // each other (the two sides of a thin part) they do not
        let flip = |tris: &mut [[u32; 3]]| tris.iter_mut().for_each(|t| t.swap(1, 2));
        for (lower_down, upper_down, across) in [
            (false, false, M * M),
            (false, true, M * M),
            (true, false, 0),
        ] {
            let (lower, mut tris) = plane(0.0);
            let (upper, mut upper_tris) = plane(0.5);
            let pos = [lower, upper].concat();
            if lower_down {
                flip(&mut tris);
            }
            if upper_down {
                flip(&mut upper_tris);
            }
            let mut all_tris = tris.to_vec();
            all_tris.extend(upper_tris.iter().map(|t| t.map(|i| i + 4)));
            let mesh = Mesh::new(Strided::from_slice(&pos), Strided::from_slice(&all_tris));
            let shells = [0, 0, 1, 1];
            let skin = Skin::new(mesh, &shells, |_| true);
            // the swapped corners swap the barycentrics
            let swapped = |mut r: Root, swap: bool| {
                if swap {
                    (r.u, r.v) = (r.v, r.u);
                }
                r
            };
            let mut roots: Vec<Root> = lattice(0)
                .into_iter()
                .map(|r| swapped(r, lower_down))
                .collect();
            roots.extend(lattice(2).into_iter().map(|r| {
                let mut r = swapped(r, upper_down);
                r.id += (M * M) as u32;
                r
            }));
            let case = (lower_down, upper_down);
            let rh = skin.r_hex(roots.len());
            let n = neighbours(&skin, &roots, 0.9);
            assert_eq!(n.close_pairs, across, "{case:?}");
            assert_eq!(n.close_across_shells, across, "{case:?}");
            // back to back: each plane sees only its own lattice
            let nearest = if across == 0 { 1.0 } else { 0.5 };
            assert!(close(n.min * rh, nearest), "{case:?}: {n:?}");
            // faces that grow no fur leave the area and the samples
            let bare = Skin::new(mesh, &shells, |f| f < 2);
            assert!(close(bare.area() as f32, skin.area() as f32 / 2.0));
            let e = empty_space(&bare, &roots[..M * M], 10, 2);
            assert!(e.p99 <= 0.578, "{e:?}");
        }
    }

    #[test]
    fn darts_keep_their_spacing_and_land_on_the_count() {
        let (pos, tris) = plane(0.0);
        let mesh = Mesh::new(Strided::from_slice(&pos), Strided::from_slice(&tris));
        let shells = [0; 2];
        let skin = Skin::new(mesh, &shells, |_| true);
        let n = 2000;
        let darts = dart_throwing(&skin, n, 5);
        assert_eq!(darts.roots.len(), n);
        let rh = skin.r_hex(n);
        let s = neighbours(&skin, &darts.roots, darts.radius);
        assert_eq!(s.close_pairs, 0);
        assert!(s.min * rh >= darts.radius * (1.0 - 1e-4));
        // a dart-throwing set is far more even than random, less than a lattice
        assert!(s.cv > 0.02 && s.cv < 0.2 && s.mean > 0.75, "{s:?}");
        for f in [0.5, 0.25] {
            let p = prefix(&skin, &darts.roots, f);
            assert!(p.cv < 0.2 && p.min > 0.6, "{f}: {p:?}");
        }
        let e = empty_space(&skin, &darts.roots, 30, 1);
        assert!(e.max < 1.3, "{e:?}");
        assert_eq!(dart_throwing(&skin, n, 5).roots, darts.roots);
    }

    #[test]
    fn faces_are_drawn_by_furred_area() {
        // a fan of faces with areas 1, 2, 4, 8 and a bald one
        let pos: Vec<[f32; 3]> = [0.0, 1.0, 3.0, 7.0, 15.0, 31.0]
            .iter()
            .flat_map(|&x| [[x, 0.0, 0.0], [x, 2.0, 0.0]])
            .collect();
        let tris: Vec<[u32; 3]> = (0..5).map(|k| [2 * k, 2 * k + 2, 2 * k + 1]).collect();
        let mesh = Mesh::new(Strided::from_slice(&pos), Strided::from_slice(&tris));
        let shells = [0; 5];
        let skin = Skin::new(mesh, &shells, |f| f < 4);
        assert_eq!(skin.area(), 15.0);
        let n = 150_000;
        let mut hits = [0usize; 5];
        for i in 0..n {
            let (face, u, v) = skin.sample(9, i, DART_COUNTERS);
            assert!(u >= 0.0 && v >= 0.0 && u + v <= 1.0);
            hits[face] += 1;
        }
        for (f, &h) in hits.iter().enumerate().take(4) {
            let want = n as f64 * (1 << f) as f64 / 15.0;
            assert!((h as f64 - want).abs() < 0.02 * want, "face {f}: {hits:?}");
        }
        assert_eq!(hits[4], 0);
    }
}
