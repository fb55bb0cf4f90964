//! The tile's dimensions, shared by the crate and the build script that
//! generates the tile.

/// Tile side, in units of the disk radius.
pub const TILE_SIDE: usize = 48;
/// Number of nested LOD levels (see [`level_spacing`]).
pub const LOD_LEVELS: usize = 12;
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
