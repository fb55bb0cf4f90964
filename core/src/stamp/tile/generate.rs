//! Generating the tile: Bridson's algorithm on the torus, coarse to fine
//! through the nested LOD steps, each step's points in farthest-point
//! order, and the points bucketed into lookup cells.
//!
//! The build script includes this file and bakes its result into the crate,
//! so a stamp pays nothing for its tile; the crate's tests include it too,
//! to check the baked tile against a fresh run.

use super::shape::{step_spacing, CELL, CELLS, LEVEL_STEPS, LOD_LEVELS, TILE_SIDE};
use crate::rng::{self, Purpose};

/// Seed of the tile's random draws. Every stamp uses this one tile, as the
/// paper uses one stamp: the stamp's seed moves each chart's window in it.
pub const SEED: u64 = 1;

const SIDE: f32 = TILE_SIDE as f32;
/// Candidates tried around each active point before it retires (Bridson's k).
const ATTEMPTS: u32 = 30;
/// Background grid cells per side during generation: cell diagonal <= 1.
const GEN_CELLS: usize = 68;
/// An upper bound on points at unit spacing on the torus (hexagonal packing).
const MAX_POINTS: usize = (2.0 * TILE_SIDE as f64 * TILE_SIDE as f64 / 1.732_050_8) as usize + 1;
/// Coordinate of an empty generation cell: far from the tile on any wrap.
const FAR: f32 = 1.0e6;

/// A generated tile: the points ordered by lookup cell (row by row), their
/// LOD steps and their order within the step (see [`step_orders`]), and
/// where each cell's points start (one entry per cell, plus the end).
pub struct Generated {
    pub points: Vec<[f32; 2]>,
    pub levels: Vec<u8>,
    pub orders: Vec<u8>,
    pub cell_start: Vec<u32>,
}

/// The tile for `seed` (same seed, same tile, on any machine: the draws are
/// counter-based and the float operations are IEEE or `libm`'s).
pub fn generate(seed: u64) -> Generated {
    let mut gen = vec![[0.0; 2]; MAX_POINTS];
    let mut gen_levels = vec![0; MAX_POINTS];
    let mut grid = vec![[0.0; 2]; GEN_CELLS * GEN_CELLS];
    let mut active = vec![0; MAX_POINTS];
    let n = bridson(seed, &mut gen, &mut gen_levels, &mut grid, &mut active);
    let gen_orders = step_orders(&gen[..n], &gen_levels[..n]);
    let mut points = vec![[0.0; 2]; n];
    let mut levels = vec![0; n];
    let mut orders = vec![0; n];
    let mut cell_start = vec![0; CELLS * CELLS + 1];
    bucket(
        &gen[..n],
        [&gen_levels[..n], &gen_orders],
        &mut points,
        [&mut levels, &mut orders],
        &mut cell_start,
    );
    Generated {
        points,
        levels,
        orders,
        cell_start,
    }
}

/// Shortest offset between two points on the torus.
#[inline]
fn wrap_delta(d: f32) -> f32 {
    if d > 0.5 * SIDE {
        d - SIDE
    } else if d < -0.5 * SIDE {
        d + SIDE
    } else {
        d
    }
}

#[inline]
pub fn torus_dist2(a: [f32; 2], b: [f32; 2]) -> f32 {
    let dx = wrap_delta(a[0] - b[0]);
    let dy = wrap_delta(a[1] - b[1]);
    dx * dx + dy * dy
}

#[inline]
fn wrap_coord(x: f32) -> f32 {
    // a coarse step throws its candidates several tiles out: whole tiles
    // come off, and rounding may land exactly on the far side
    let w = x - SIDE * libm::floorf(x / SIDE);
    if (0.0..SIDE).contains(&w) {
        w
    } else {
        0.0
    }
}

/// Bridson's algorithm on the torus, coarse to fine: step `j` of level `k`
/// grows, from every point placed so far, new points at least
/// [`step_spacing`]`(k, j)` from all of them until none fits, and gives
/// them the value `k * LEVEL_STEPS + j` in `levels`. Each step's prefix is
/// then a Poisson set grown at its own spacing, as the next step's points
/// are thrown around it: a rank prefix is as even as a set made for its
/// size, where levels picked afterwards from one finished set are not (they
/// can only take the points it has). `grid` holds the point of each
/// generation cell (at most one fits at the finest spacing), or a far
/// sentinel.
fn bridson(
    seed: u64,
    points: &mut [[f32; 2]],
    levels: &mut [u8],
    grid: &mut [[f32; 2]],
    active: &mut [u32],
) -> usize {
    let h = SIDE / GEN_CELLS as f32;
    let cell_of = |p: [f32; 2]| {
        let x = ((p[0] / h) as usize).min(GEN_CELLS - 1);
        let y = ((p[1] / h) as usize).min(GEN_CELLS - 1);
        y * GEN_CELLS + x
    };
    grid.fill([FAR; 2]);
    let mut draw = 0u32;
    let mut next = || {
        draw += 1;
        rng::unit(seed, 0, Purpose::TileCandidate, draw)
    };
    let first = [next() * SIDE, next() * SIDE];
    points[0] = first;
    levels[0] = 0;
    grid[cell_of(first)] = first;
    let mut n = 1usize;
    for step in 0..LOD_LEVELS * LEVEL_STEPS {
        let s = step_spacing(step / LEVEL_STEPS, step % LEVEL_STEPS);
        for (slot, a) in active[..n].iter_mut().enumerate() {
            *a = slot as u32;
        }
        let mut n_active = n;
        while n_active > 0 {
            let slot = ((next() * n_active as f32) as usize).min(n_active - 1);
            let centre = points[active[slot] as usize];
            let mut placed = false;
            for _ in 0..ATTEMPTS {
                let angle = next() * core::f32::consts::TAU;
                let radius = s * libm::sqrtf(1.0 + 3.0 * next());
                let p = [
                    wrap_coord(centre[0] + radius * libm::cosf(angle)),
                    wrap_coord(centre[1] + radius * libm::sinf(angle)),
                ];
                if n < points.len() && fits(p, s, &points[..n], grid, h) {
                    points[n] = p;
                    levels[n] = step as u8;
                    grid[cell_of(p)] = p;
                    active[n_active] = n as u32;
                    n += 1;
                    n_active += 1;
                    placed = true;
                    break;
                }
            }
            if !placed {
                n_active -= 1;
                active[slot] = active[n_active];
            }
        }
    }
    n
}

/// Whether `p` is at least `s` from every point: from those in the
/// generation cells within `s` of it while they are fewer than the points,
/// else from the list of `points` (the coarse steps).
fn fits(p: [f32; 2], s: f32, points: &[[f32; 2]], grid: &[[f32; 2]], h: f32) -> bool {
    let s2 = s * s;
    let reach = libm::ceilf(s / h) as isize;
    let g = GEN_CELLS as isize;
    if 2 * reach + 1 >= g || (2 * reach + 1).pow(2) >= points.len() as isize {
        return points.iter().all(|&q| torus_dist2(p, q) >= s2);
    }
    let cx = (p[0] / h) as isize;
    let cy = (p[1] / h) as isize;
    (-reach..=reach).all(|dy| {
        let row = (cy + dy).rem_euclid(g) as usize * GEN_CELLS;
        (-reach..=reach)
            .all(|dx| torus_dist2(p, grid[row + (cx + dx).rem_euclid(g) as usize]) >= s2)
    })
}

/// Counting sort of the points and their two bytes (step, order) into
/// cells (stable, so deterministic).
fn bucket(
    src: &[[f32; 2]],
    src_bytes: [&[u8]; 2],
    dst: &mut [[f32; 2]],
    bytes: [&mut [u8]; 2],
    cell_start: &mut [u32],
) {
    let at = |x: f32| (x as usize / CELL).min(CELLS - 1);
    let cell = |p: [f32; 2]| at(p[1]) * CELLS + at(p[0]);
    cell_start.fill(0);
    for &p in src {
        cell_start[cell(p) + 1] += 1;
    }
    for c in 0..CELLS * CELLS {
        cell_start[c + 1] += cell_start[c];
    }
    let mut fill = [0u32; CELLS * CELLS];
    let [levels, orders] = bytes;
    for (i, &p) in src.iter().enumerate() {
        let c = cell(p);
        let at = (cell_start[c] + fill[c]) as usize;
        dst[at] = p;
        levels[at] = src_bytes[0][i];
        orders[at] = src_bytes[1][i];
        fill[c] += 1;
    }
}

/// Each point's place in its step, as a byte: the step's points in
/// farthest-point order (each next one the farthest from every point of
/// the coarser steps and the step's points before it; ties go to the lower
/// index), scaled to 0..=255. A rank prefix that ends inside a step then
/// takes its points where they are most wanted, and the count trim, which
/// drops the end of the last step, drops the points nearest to others:
/// where the roots are densest, so no hole opens.
fn step_orders(points: &[[f32; 2]], levels: &[u8]) -> Vec<u8> {
    let mut orders = vec![0; points.len()];
    let mut gap = vec![f32::INFINITY; points.len()];
    for step in 0..(LOD_LEVELS * LEVEL_STEPS) as u8 {
        let members: Vec<usize> = (0..points.len()).filter(|&i| levels[i] == step).collect();
        for &i in &members {
            gap[i] = (0..points.len())
                .filter(|&j| levels[j] < step)
                .map(|j| torus_dist2(points[i], points[j]))
                .fold(f32::INFINITY, f32::min);
        }
        let mut left = members.clone();
        for k in 0..members.len() {
            let (slot, _) =
                left.iter()
                    .enumerate()
                    .fold((0, f32::NEG_INFINITY), |best, (s, &i)| {
                        if gap[i] > best.1 {
                            (s, gap[i])
                        } else {
                            best
                        }
                    });
            let chosen = left.remove(slot);
            orders[chosen] = (k * 256 / members.len()) as u8;
            for &i in &left {
                gap[i] = gap[i].min(torus_dist2(points[i], points[chosen]));
            }
        }
    }
    orders
}
