//! The fill pass: darts thrown where the edge pass leaves holes.
//!
//! Along a cut edge two pieces of the tile meet at random, and the edge
//! pass drops one point of each pair that comes too close; nothing refills
//! the room either leaves. After the edge pass, every face with a cut edge
//! takes darts at random in its triangle, [`DARTS_PER_ROOT`] for each root
//! it holds on average; a dart counts only where its disk reaches past the
//! face's boundary (where the tile leaves holes), and stays when it is at
//! least the disk radius from every point kept so far (the edge pass's
//! rule: the pair's larger density scale, points of opposed faces never
//! clash), as the finest LOD level. Faces go in order and each face's darts
//! in order, so the result does not depend on how the stamp was split.

use super::near::{Near, LANES};
use super::place::Placing;
use super::{face_frame, Candidate, Scratch, Stamper, SMALL_TARGET};
use crate::rng::{self, Purpose};
use crate::stamp::tile::{LEVEL_STEPS, LOD_LEVELS, TILE};
use crate::surface::grid::HashGrid;
use crate::Error;
use glam::Vec3;

/// Darts a face takes per root it holds on average.
pub(super) const DARTS_PER_ROOT: f32 = 3.0;
/// Darts of one face tested together (a face with more takes them in runs).
const RUN: usize = 64;
/// Grid cells of the fill, in disk radii.
const FILL_GRID_CELL: f32 = 2.0;

impl<'m, 'a> Stamper<'m, 'a> {
    /// Fills holes after the edge pass: `cands[..kept]` are the kept
    /// candidates in face order; darts that stay are written after them.
    /// Returns the new count (at most the room in `cands` and `scratch`).
    ///
    /// Stamps of fewer than [`SMALL_TARGET`] roots are not filled: their
    /// count is a lottery over the tile's windows already, and darts would
    /// make it jump further between passes.
    pub fn fill(
        &self,
        cands: &mut [Candidate],
        kept: usize,
        scratch: &mut Scratch,
    ) -> Result<usize, Error> {
        if !self.fixed && self.target < SMALL_TARGET {
            return Ok(kept);
        }
        let room = cands.len().min(scratch.next.len());
        scratch.check(kept)?;
        let buckets = HashGrid::buckets_for(room).min(scratch.heads.len());
        let mut grid = HashGrid::new(
            &mut scratch.heads[..buckets],
            scratch.next,
            FILL_GRID_CELL * self.radius,
        );
        let near = &mut *scratch.near;
        let mut frame = (u32::MAX, [Vec3::ZERO; 3]);
        for (i, c) in cands[..kept].iter().enumerate() {
            if c.face != frame.0 {
                frame = (c.face, face_frame(&self.mesh, c.face as usize));
            }
            near[i] = Near::new(c, i, &frame.1);
            grid.insert(i as u32, Vec3::from(near[i].position));
        }
        let squares = self.spacings.map(|s| s * s);
        let mut n = kept;
        // the face's own kept points: a run of the face-ordered candidates
        let mut own = 0;
        for f in 0..self.faces.len() {
            let face = &self.faces[f];
            let place = &self.places[f];
            while own < kept && (cands[own].face as usize) < f {
                own += 1;
            }
            if face.scale == 0.0 || place.edges & 7 == 7 || n == room {
                continue;
            }
            let own_end = own
                + cands[own..kept]
                    .iter()
                    .take_while(|c| c.face as usize == f)
                    .count();
            let r = self.local_radius(f as u32);
            let expected = self.mesh.area(f) * TILE.density() / (r * r);
            let darts = libm::ceilf(DARTS_PER_ROOT * expected) as usize;
            let placing = Placing::new(place, 1.0 / self.radius);
            let frame = face_frame(&self.mesh, f);
            let first_dart = n;
            for start in (0..darts).step_by(RUN) {
                let count = RUN.min(darts - start);
                let mut group = [Near::default(); RUN];
                let mut uv = [[0.0f32; 2]; RUN];
                let mut m = 0;
                let (mut xs, mut ys) = ([0.0f32; RUN], [0.0f32; RUN]);
                for d in 0..count {
                    let key = (f as u64) << 20 | (start + d) as u64;
                    let (s, t) = (
                        rng::unit(self.seed, key, Purpose::FillDart, 0),
                        rng::unit(self.seed, key, Purpose::FillDart, 1),
                    );
                    // uniform in the triangle
                    let (u, v) = if s + t > 1.0 {
                        (1.0 - s, 1.0 - t)
                    } else {
                        (s, t)
                    };
                    uv[d] = [u, v];
                    let p = placing.tile_point(u, v);
                    (xs[d], ys[d]) = (p.x, p.y);
                }
                let mut levels = [0u16; RUN];
                let lanes = count.div_ceil(LANES) * LANES;
                placing.near_levels(&xs[..lanes], &ys[..lanes], &squares, &mut levels);
                for d in 0..count {
                    let c = Candidate {
                        face: f as u32,
                        uv: uv[d],
                        level: (LOD_LEVELS - 1) as u8,
                        step: (LEVEL_STEPS - 1) as u8,
                        near_levels: LOD_LEVELS as u16,
                    };
                    let q = Near::new(&c, n, &frame);
                    // away from the boundary the tile leaves no hole
                    if levels[d] as usize == LOD_LEVELS
                        && !self.shells.buried(
                            Vec3::from(q.position),
                            Vec3::from(face.normal),
                            super::place::BURY_LIFT * r,
                        )
                    {
                        group[m] = q;
                        uv[m] = uv[d];
                        m += 1;
                    }
                }
                if m == 0 {
                    continue;
                }
                let group = &group[..m];
                let mut clashed = [false; RUN];
                let buf = &mut scratch.gathered;
                Self::gather(&grid, near, group, r * 1.0001, buf, |buf| {
                    self.weigh(buf, f as u32, |scale| {
                        let r = self.radius / scale;
                        r * r
                    });
                    for (hit, q) in clashed.iter_mut().zip(group) {
                        *hit = *hit || buf.clashes(q.position);
                    }
                });
                // the face's own points and darts are not in the gathered
                // set (it holds other faces only)
                let r2 = r * r;
                for (d, q) in group.iter().enumerate() {
                    let p = Vec3::from(q.position);
                    let close = |i: usize| Vec3::from(near[i].position).distance_squared(p) < r2;
                    if clashed[d] || (own..own_end).any(close) || (first_dart..n).any(close) {
                        continue;
                    }
                    if n == room {
                        break;
                    }
                    cands[n] = Candidate {
                        face: f as u32,
                        uv: uv[d],
                        level: (LOD_LEVELS - 1) as u8,
                        step: (LEVEL_STEPS - 1) as u8,
                        near_levels: LOD_LEVELS as u16,
                    };
                    near[n] = Near {
                        index: n as u32,
                        ..*q
                    };
                    grid.insert(n as u32, p);
                    n += 1;
                }
            }
        }
        Ok(n)
    }
}
