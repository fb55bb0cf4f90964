//! Generating the tile: Bridson's algorithm on the torus, the points
//! bucketed into lookup cells, and their nested LOD levels.
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
/// LOD levels, and where each cell's points start (one entry per cell,
/// plus the end).
pub struct Generated {
    pub points: Vec<[f32; 2]>,
    pub levels: Vec<u8>,
    pub cell_start: Vec<u32>,
}

/// The tile for `seed` (same seed, same tile, on any machine: the draws are
/// counter-based and the float operations are IEEE or `libm`'s).
pub fn generate(seed: u64) -> Generated {
    let mut gen = vec![[0.0; 2]; MAX_POINTS];
    let mut grid = vec![[0.0; 2]; GEN_CELLS * GEN_CELLS];
    let mut active = vec![0; MAX_POINTS];
    let n = bridson(seed, &mut gen, &mut grid, &mut active);
    let mut points = vec![[0.0; 2]; n];
    let mut cell_start = vec![0; CELLS * CELLS + 1];
    bucket(&gen[..n], &mut points, &mut cell_start);
    let mut levels = vec![0; n];
    assign_levels(&points, &cell_start, &mut levels);
    Generated {
        points,
        levels,
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
    // x is within 2 of the tile: one add or subtract brings it back, and
    // rounding may land exactly on the far side
    let w = if x < 0.0 {
        x + SIDE
    } else if x >= SIDE {
        x - SIDE
    } else {
        x
    };
    if w < SIDE {
        w
    } else {
        0.0
    }
}

/// Bridson's algorithm on the torus. `grid` holds the point of each
/// generation cell (at most one fits), or a far sentinel.
fn bridson(seed: u64, points: &mut [[f32; 2]], grid: &mut [[f32; 2]], active: &mut [u32]) -> usize {
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
    grid[cell_of(first)] = first;
    active[0] = 0;
    let (mut n, mut n_active) = (1usize, 1usize);
    while n_active > 0 {
        let slot = ((next() * n_active as f32) as usize).min(n_active - 1);
        let centre = points[active[slot] as usize];
        let mut placed = false;
        for _ in 0..ATTEMPTS {
            let angle = next() * core::f32::consts::TAU;
            let radius = libm::sqrtf(1.0 + 3.0 * next());
            let p = [
                wrap_coord(centre[0] + radius * libm::cosf(angle)),
                wrap_coord(centre[1] + radius * libm::sinf(angle)),
            ];
            if n < points.len() && fits(p, grid, h) {
                points[n] = p;
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
    n
}

/// Whether `p` is at least 1 from every point in the 5x5 generation cells
/// around it, nearest cells first: most candidates fail, and they fail there.
fn fits(p: [f32; 2], grid: &[[f32; 2]], h: f32) -> bool {
    const ORDER: [(isize, isize); 25] = {
        let mut order = [(0, 0); 25];
        let mut i = 0;
        let mut ring = 0;
        while ring <= 2 {
            let mut dy = -2;
            while dy <= 2 {
                let mut dx = -2;
                while dx <= 2 {
                    let r = if dx * dx > dy * dy { dx * dx } else { dy * dy };
                    if r == ring * ring {
                        order[i] = (dx, dy);
                        i += 1;
                    }
                    dx += 1;
                }
                dy += 1;
            }
            ring += 1;
        }
        order
    };
    let g = GEN_CELLS as isize;
    let wrap = |c: isize| {
        (if c < 0 {
            c + g
        } else if c >= g {
            c - g
        } else {
            c
        }) as usize
    };
    let cx = (p[0] / h) as isize;
    let cy = (p[1] / h) as isize;
    ORDER
        .iter()
        .all(|&(dx, dy)| torus_dist2(p, grid[wrap(cy + dy) * GEN_CELLS + wrap(cx + dx)]) >= 1.0)
}

/// Counting sort of the points into cells (stable, so deterministic).
fn bucket(src: &[[f32; 2]], dst: &mut [[f32; 2]], cell_start: &mut [u32]) {
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
    for &p in src {
        let c = cell(p);
        dst[(cell_start[c] + fill[c]) as usize] = p;
        fill[c] += 1;
    }
}

/// Greedy nested selection, step by step: step `j` of level `k` takes every
/// point still free that is at least [`step_spacing`]`(k, j)` from every
/// point taken before, so level `k`'s points (all its steps) are at least
/// `level_spacing(k)` apart from every point of level `<= k`, and each level
/// prefix is itself a Poisson set with about half the density of the next.
/// A point's value is `level * LEVEL_STEPS + step`. `points` are bucketed
/// by `cell_start`; each point is tested against the taken ones in the
/// cells within the spacing, or against the list of taken ones when that is
/// shorter (the coarse levels), which tests the same points.
fn assign_levels(points: &[[f32; 2]], cell_start: &[u32], levels: &mut [u8]) {
    const FREE: u8 = u8::MAX;
    levels.fill(FREE);
    let mut chosen = [0u32; MAX_POINTS];
    let mut n_chosen = 0;
    let side = CELLS as isize;
    for k in 0..LOD_LEVELS {
        for j in 0..LEVEL_STEPS {
            let r = step_spacing(k, j);
            let r2 = r * r;
            let reach = libm::ceilf(r / CELL as f32) as isize;
            let by_cells = 2 * reach < side;
            for i in 0..points.len() {
                if levels[i] != FREE {
                    continue;
                }
                let p = points[i];
                let far = |j: usize| torus_dist2(p, points[j]) >= r2;
                let free = if by_cells && (2 * reach + 1).pow(2) < n_chosen as isize {
                    let (cx, cy) = (p[0] as isize / CELL as isize, p[1] as isize / CELL as isize);
                    (-reach..=reach).all(|dy| {
                        let row = (cy + dy).rem_euclid(side) * side;
                        (-reach..=reach).all(|dx| {
                            let c = (row + (cx + dx).rem_euclid(side)) as usize;
                            let cell = cell_start[c] as usize..cell_start[c + 1] as usize;
                            cell.into_iter().all(|j| levels[j] == FREE || far(j))
                        })
                    })
                } else {
                    chosen[..n_chosen].iter().all(|&j| far(j as usize))
                };
                if free {
                    levels[i] = (k * LEVEL_STEPS + j) as u8;
                    chosen[n_chosen] = i as u32;
                    n_chosen += 1;
                }
            }
        }
    }
    // the last step's spacing is the tile's own: it takes every point left
    debug_assert!(levels.iter().all(|&l| l != FREE));
}
