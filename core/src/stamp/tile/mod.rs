//! The Poisson stamp: a periodic 2D Poisson-disk tile (Bridson's algorithm)
//! with a nested LOD level per point.
//!
//! The paper's stamp is a rectangle big enough to hold any triangle. A
//! periodic tile does the same job for triangles of any size (they wrap
//! around it) and keeps the stamp small enough to stay in cache. Like the
//! paper's stamp it is made once: the build script generates it (see
//! `generate.rs`) and bakes it into the crate as [`TILE`].

#[cfg(test)]
mod generate;
mod shape;

pub use shape::{level_spacing, step_spacing, CELL, CELLS, LEVEL_STEPS, LOD_LEVELS, TILE_SIDE};

// the baked tile: `POINTS`, `LEVELS` and `CELL_START`, as the fields of `Tile`
include!(concat!(env!("OUT_DIR"), "/tile.rs"));

/// A periodic Poisson-disk point set of side [`TILE_SIDE`] and spacing 1,
/// bucketed into cells of side [`CELL`] for lookups.
pub struct Tile {
    points: &'static [[f32; 2]],
    levels: &'static [u8],
    orders: &'static [u8],
    cell_start: &'static [u32],
}

/// The tile every stamp takes its points from.
pub static TILE: Tile = Tile {
    points: &POINTS,
    levels: &LEVELS,
    orders: &ORDERS,
    cell_start: &CELL_START,
};

impl Tile {
    /// Number of points in the tile.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when the tile holds no point (never).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Points per unit area (the disk radius is the unit).
    pub fn density(&self) -> f32 {
        self.points.len() as f32 / (TILE_SIDE * TILE_SIDE) as f32
    }

    /// Points of the `len` cells (x, y) to (x + len - 1, y) of one row,
    /// their LOD steps (`level * LEVEL_STEPS + step`, see
    /// [`step_spacing`]) and their orders within the step (0 first, 255
    /// last: the farthest-point order of the step, scaled): cells are stored
    /// row by row, so a run of cells is one slice. `x + len <= CELLS`, `y <
    /// CELLS`.
    #[inline]
    pub fn run(&self, x: usize, y: usize, len: usize) -> (&[[f32; 2]], &[u8], &[u8]) {
        let c = y * CELLS + x;
        let (s, e) = (
            self.cell_start[c] as usize,
            self.cell_start[c + len] as usize,
        );
        (&self.points[s..e], &self.levels[s..e], &self.orders[s..e])
    }

    /// All points with their LOD steps (`level * LEVEL_STEPS + step`).
    pub fn points(&self) -> impl Iterator<Item = ([f32; 2], u8)> + '_ {
        self.points.iter().copied().zip(self.levels.iter().copied())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use generate::{generate, torus_dist2, SEED};

    #[test]
    fn the_baked_tile_is_the_generated_one() {
        let fresh = generate(SEED);
        let bits = |p: &[[f32; 2]]| p.iter().map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(TILE.points), bits(&fresh.points));
        assert_eq!(TILE.levels, &fresh.levels[..]);
        assert_eq!(TILE.orders, &fresh.orders[..]);
        assert_eq!(TILE.cell_start, &fresh.cell_start[..]);
    }

    #[test]
    fn cells_hold_the_points_inside_them() {
        for y in 0..CELLS {
            for x in 0..CELLS {
                for p in TILE.run(x, y, 1).0 {
                    let c = p.map(|v| v as usize / CELL);
                    assert_eq!((c[0], c[1]), (x, y), "{p:?}");
                }
            }
        }
        assert_eq!(TILE.cell_start[CELLS * CELLS] as usize, TILE.len());
    }

    #[test]
    fn tile_is_a_periodic_poisson_set_with_nested_levels() {
        let all: Vec<([f32; 2], u8)> = TILE.points().collect();
        assert!(
            TILE.density() > 0.55 && TILE.density() < 0.8,
            "{}",
            TILE.density()
        );
        // every pair respects the spacing of the later step of the two
        for (i, &(a, sa)) in all.iter().enumerate() {
            for &(b, sb) in &all[i + 1..] {
                let d2 = torus_dist2(a, b);
                assert!(d2 >= 0.999, "points too close: {d2}");
                let s = sa.max(sb) as usize;
                let r = step_spacing(s / LEVEL_STEPS, s % LEVEL_STEPS);
                assert!(d2 >= r * r * 0.999, "step {s} spacing violated");
            }
        }
        let mut per_level = [0usize; LOD_LEVELS];
        for p in &all {
            per_level[p.1 as usize / LEVEL_STEPS] += 1;
        }
        // each level about doubles the points of the levels before it
        for k in 6..LOD_LEVELS {
            let before: usize = per_level[..k].iter().sum();
            let ratio = (before + per_level[k]) as f32 / before as f32;
            assert!((1.5..2.8).contains(&ratio), "level {k}: {per_level:?}");
        }
        let finest = per_level[LOD_LEVELS - 1];
        let share = finest as f32 / all.len() as f32;
        assert!(share > 0.3 && share < 0.7, "finest level holds {share}");
    }
}
