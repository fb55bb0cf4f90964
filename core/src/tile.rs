//! The Poisson stamp: a periodic 2D Poisson-disk tile (Bridson's algorithm)
//! with a nested LOD level per point.
//!
//! The paper's stamp is a rectangle big enough to hold any triangle. A
//! periodic tile does the same job for triangles of any size (they wrap
//! around it) and keeps the stamp small enough to stay in cache.

use crate::arena::{Arena, ArenaLayout};
use crate::rng::{self, Purpose};
use crate::Error;

/// Tile side, in units of the disk radius.
pub const TILE_SIDE: usize = 48;
/// Number of nested LOD levels; level `k` has spacing `sqrt(2)^(LOD_LEVELS - 1 - k)`.
pub const LOD_LEVELS: usize = 12;

const SIDE: f32 = TILE_SIDE as f32;
/// Side of the lookup cells, in units of the disk radius. Placing a
/// triangle walks the cells it crosses row by row: cells of 2 hold about
/// three points, so the walk takes half the rows and runs that unit cells
/// take, for about a fifth more points tested (cheap, branch-free tests).
pub const CELL: usize = 2;
/// Lookup cells per tile side.
pub const CELLS: usize = TILE_SIDE / CELL;
/// Candidates tried around each active point before it retires (Bridson's k).
const ATTEMPTS: u32 = 30;
/// Background grid cells per side during generation: cell diagonal <= 1.
const GEN_CELLS: usize = 68;
/// An upper bound on points at unit spacing on the torus (hexagonal packing).
const MAX_POINTS: usize = (2.0 * TILE_SIDE as f64 * TILE_SIDE as f64 / 1.732_050_8) as usize + 1;
/// Coordinate of an empty generation cell: far from the tile on any wrap.
const FAR: f32 = 1.0e6;

/// A periodic Poisson-disk point set of side [`TILE_SIDE`] and spacing 1,
/// bucketed into cells of side [`CELL`] for lookups.
pub struct Tile<'a> {
    points: &'a [[f32; 2]],
    levels: &'a [u8],
    cell_start: &'a [u32],
}

impl<'a> Tile<'a> {
    /// Adds the arena bytes [`Tile::build`] needs to `layout`.
    pub fn layout(layout: &mut ArenaLayout) {
        layout
            .add::<[f32; 2]>(MAX_POINTS * 2)
            .add::<u8>(MAX_POINTS)
            .add::<u32>(CELLS * CELLS + 1)
            .add::<[f32; 2]>(GEN_CELLS * GEN_CELLS)
            .add::<u32>(MAX_POINTS);
    }

    /// Generates the tile for `seed` (same seed, same tile, on any machine).
    pub fn build(seed: u64, arena: &mut Arena<'a>) -> Result<Self, Error> {
        let gen = arena.alloc::<[f32; 2]>(MAX_POINTS)?;
        let points = arena.alloc::<[f32; 2]>(MAX_POINTS)?;
        let levels = arena.alloc::<u8>(MAX_POINTS)?;
        let cell_start = arena.alloc::<u32>(CELLS * CELLS + 1)?;
        let grid = arena.alloc::<[f32; 2]>(GEN_CELLS * GEN_CELLS)?;
        let active = arena.alloc::<u32>(MAX_POINTS)?;
        let n = bridson(seed, gen, grid, active);
        bucket(&gen[..n], points, cell_start);
        let points = &points[..n];
        assign_levels(points, cell_start, &mut levels[..n]);
        Ok(Tile {
            points,
            levels: &levels[..n],
            cell_start,
        })
    }

    /// Number of points in the tile.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when the tile holds no point (never, once built).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Points per unit area (the disk radius is the unit).
    pub fn density(&self) -> f32 {
        self.points.len() as f32 / (SIDE * SIDE)
    }

    /// Points of the `len` cells (x, y) to (x + len - 1, y) of one row,
    /// and their LOD levels: cells are stored row by row, so a run of cells
    /// is one slice. `x + len <= CELLS`, `y < CELLS`.
    #[inline]
    pub fn run(&self, x: usize, y: usize, len: usize) -> (&[[f32; 2]], &[u8]) {
        let c = y * CELLS + x;
        let (s, e) = (
            self.cell_start[c] as usize,
            self.cell_start[c + len] as usize,
        );
        (&self.points[s..e], &self.levels[s..e])
    }

    /// All points with their LOD levels.
    pub fn points(&self) -> impl Iterator<Item = ([f32; 2], u8)> + '_ {
        self.points.iter().copied().zip(self.levels.iter().copied())
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
fn torus_dist2(a: [f32; 2], b: [f32; 2]) -> f32 {
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

/// Greedy nested selection: level `k` points are at least `sqrt(2)^(L-1-k)`
/// apart from every point of level `<= k`, so each level prefix is itself a
/// Poisson set with half the density of the next. `points` are bucketed by
/// `cell_start`; each point is tested against the chosen ones in the cells
/// within the spacing, or against the list of chosen ones when that is
/// shorter (the coarse levels), which tests the same points.
fn assign_levels(points: &[[f32; 2]], cell_start: &[u32], levels: &mut [u8]) {
    let finest = (LOD_LEVELS - 1) as u8;
    levels.fill(finest);
    let mut chosen = [0u32; MAX_POINTS];
    let mut n_chosen = 0;
    let side = CELLS as isize;
    for k in 0..finest {
        let r = libm::powf(2.0, 0.5 * (finest - k) as f32);
        let r2 = r * r;
        let reach = libm::ceilf(r / CELL as f32) as isize;
        let by_cells = 2 * reach < side;
        for i in 0..points.len() {
            if levels[i] != finest {
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
                        cell.into_iter().all(|j| levels[j] == finest || far(j))
                    })
                })
            } else {
                chosen[..n_chosen].iter().all(|&j| far(j as usize))
            };
            if free {
                levels[i] = k;
                chosen[n_chosen] = i as u32;
                n_chosen += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_tile(f: impl FnOnce(&Tile)) {
        let mut layout = ArenaLayout::new();
        Tile::layout(&mut layout);
        let mut buf = [0u8; 200_000];
        assert!(layout.bytes() <= buf.len());
        let mut arena = Arena::new(&mut buf);
        let tile = Tile::build(42, &mut arena).unwrap();
        f(&tile);
    }

    #[test]
    fn tile_is_a_periodic_poisson_set_with_nested_levels() {
        with_tile(|tile| {
            let all: Vec<([f32; 2], u8)> = tile.points().collect();
            assert!(
                tile.density() > 0.55 && tile.density() < 0.8,
                "{}",
                tile.density()
            );
            for (i, &(a, la)) in all.iter().enumerate() {
                for &(b, lb) in &all[i + 1..] {
                    let d2 = torus_dist2(a, b);
                    assert!(d2 >= 0.999, "points too close: {d2}");
                    let k = la.max(lb);
                    let r = libm::powf(2.0, 0.5 * (LOD_LEVELS - 1 - k as usize) as f32);
                    assert!(d2 >= r * r * 0.999, "level {k} spacing violated");
                }
            }
            let finest = all
                .iter()
                .filter(|p| p.1 as usize == LOD_LEVELS - 1)
                .count();
            let share = finest as f32 / all.len() as f32;
            assert!(share > 0.3 && share < 0.7, "finest level holds {share}");
        });
    }
}
