//! The tile's dimensions, shared by the crate and the build script that
//! generates the tile.

/// Tile side, in units of the disk radius.
pub const TILE_SIDE: usize = 48;
/// Number of nested LOD levels (see [`level_spacing`]).
pub const LOD_LEVELS: usize = 12;
/// Steps each level's points are chosen in, at spacings from just under the
/// next coarser level's down to the level's own: a rank prefix that ends
/// inside a level then takes its points step by step, the earlier steps
/// spread wider, instead of a random share of the level.
pub const LEVEL_STEPS: usize = 4;
/// Side of the lookup cells, in units of the disk radius. Placing a
/// triangle walks the cells it crosses row by row: cells of 2 hold about
/// three points, so the walk takes half the rows and runs that unit cells
/// take, for about a fifth more points tested (cheap, branch-free tests).
pub const CELL: usize = 2;
/// Lookup cells per tile side.
pub const CELLS: usize = TILE_SIDE / CELL;

/// The spacing of LOD level `k` in units of the disk radius:
/// `sqrt(2)^(LOD_LEVELS - 1 - k)`, so `sqrt(2)` between levels and 1 at the
/// finest.
pub fn level_spacing(k: usize) -> f32 {
    libm::powf(2.0, 0.5 * (LOD_LEVELS - 1 - k) as f32)
}

/// The spacing of step `j` of level `k`: `level_spacing(k) *
/// 2^((LEVEL_STEPS - 1 - j) / (2 LEVEL_STEPS))`, from just under the
/// coarser level's spacing (`j = 0`) to the level's own (the last step).
pub fn step_spacing(k: usize, j: usize) -> f32 {
    let above = (LEVEL_STEPS - 1 - j) as f32 / (2 * LEVEL_STEPS) as f32;
    level_spacing(k) * libm::powf(2.0, above)
}
