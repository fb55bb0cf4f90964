//! The fill pass: darts thrown where the edge pass leaves holes.
//!
//! Along a cut edge two pieces of the tile meet at random, and the edge
//! pass drops one point of each pair that comes too close; nothing refills
//! the room either leaves. After the edge pass, each cut edge takes darts
//! at random in the strip of its face within the local disk radius of it,
//! [`DARTS_PER_ROOT`] for each root such a strip holds on average. Where
//! the edge of buried skin crosses a face (another shell passes through
//! it), the placement dropped the points on the buried side and nothing
//! refilled the skin beside them: such a face takes its darts anywhere on
//! it, as many per root it holds. A dart
//! stays when it is at least its face's local disk radius from every point
//! kept so far (points of opposed faces never clash) and its skin is not
//! buried, as the finest LOD level. Faces go in order, and each face's edges and darts in order, so
//! the result does not depend on how the stamp was split.

use super::near::Near;
use super::{face_frame, Candidate, Scratch, Stamper, SMALL_TARGET};
use crate::rng::{self, Purpose};
use crate::stamp::tile::{LEVEL_STEPS, LOD_LEVELS, TILE};
use crate::surface::grid::HashGrid;
use crate::Error;
use glam::Vec3;

/// Darts a cut edge's strip takes per root it holds on average: with 6,
/// 1M roots on the creature keep no hole wider than 1.1 r_hex (2 leave
/// holes up to 1.5).
pub(super) const DARTS_PER_ROOT: f32 = 6.0;
/// Share of the edge pass's loss the fill wins back, as `REFILLED +
/// REFILL_SLOPE * loss / target`: where the loss is a larger share of the
/// roots (fewer roots, so more cut edge per root) the darts also fill gaps
/// the tile left along cut edges, and win back more than the loss. The
/// radius is first predicted with the rest of the loss; with these values
/// the first pass lands in the count band on the creature and the head at
/// every count from 3K to 1M (seeds 1 and 2; a slope of 2 missed at 10K
/// and below, which cost a second pass).
pub(super) const REFILLED: f32 = 0.82;
/// See [`REFILLED`].
pub(super) const REFILL_SLOPE: f32 = 1.4;
/// Darts of one face tested together (a face with more takes them in runs).
const RUN: usize = 256;
/// Barycentric `(u, v)` of each corner.
const BARY: [[f32; 2]; 3] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];

/// A dart at `uv` on face `f`: the finest LOD step, near every boundary,
/// first in its step (it fills a hole: the count trim drops it last).
fn dart(f: usize, uv: [f32; 2]) -> Candidate {
    Candidate {
        face: f as u32,
        uv,
        level: (LOD_LEVELS - 1) as u8,
        step: (LEVEL_STEPS - 1) as u8,
        order: 0,
        near_levels: LOD_LEVELS as u8,
    }
}

/// Grid cells of the fill, in disk radii.
const FILL_GRID_CELL: f32 = 6.0;
/// Most kept points of a face its darts are tested against in lanes (a
/// face with more tests them one by one), and most darts a face keeps
/// that its later darts are tested against in lanes.
pub(super) const OWN: usize = 1024;
#[cfg(test)]
std::thread_local! {
    /// Faces whose darts a fill on this thread tested point by point (more
    /// kept points than [`OWN`]), for the test that must reach that path.
    pub(super) static POINT_BY_POINT: core::cell::Cell<usize> = const { core::cell::Cell::new(0) };
}

/// Lanes of [`Own::clashes`].
const OWN_LANES: usize = 8;

/// Points of one face its darts may clash with, in lanes (one buffer
/// reused from face to face): the face's kept points (those the fill's
/// grid holds, see `close` in [`Stamper::fill`]), or the darts it kept so
/// far. Each dart is tested against them in a vector loop, where a test
/// per point read each from the records.
struct Own {
    x: [f32; OWN],
    y: [f32; OWN],
    z: [f32; OWN],
    /// Points held.
    len: usize,
    /// Points, rounded up to whole lanes (the rest at infinity).
    lanes: usize,
    /// Whether every point given since the last `set` is held (none is
    /// when more than [`OWN`] were given).
    whole: bool,
}

impl Own {
    fn new() -> Self {
        Own {
            x: [0.0; OWN],
            y: [0.0; OWN],
            z: [0.0; OWN],
            len: 0,
            lanes: 0,
            whole: true,
        }
    }

    /// Holds the `points`; false (and holds none) when there are more than
    /// [`OWN`].
    fn set(&mut self, points: impl Iterator<Item = [f32; 3]>) -> bool {
        (self.len, self.lanes, self.whole) = (0, 0, true);
        points.for_each(|p| self.push(p));
        self.whole
    }

    /// Holds `p` too; holds none from then on when [`OWN`] are held.
    fn push(&mut self, p: [f32; 3]) {
        if !self.whole {
            return;
        }
        if self.len == OWN {
            (self.len, self.lanes, self.whole) = (0, 0, false);
            return;
        }
        let n = self.len;
        if n == self.lanes {
            self.lanes += OWN_LANES;
            for a in [&mut self.x, &mut self.y, &mut self.z] {
                a[n..self.lanes].fill(f32::INFINITY);
            }
        }
        (self.x[n], self.y[n], self.z[n]) = (p[0], p[1], p[2]);
        self.len += 1;
    }

    /// Whether a point is closer to `at` than `sqrt(r2)`: the same test,
    /// operation for operation, as `distance_squared(at) < r2`.
    #[inline(always)]
    fn clashes(&self, at: Vec3, r2: f32) -> bool {
        let (xs, ys, zs) = (
            &self.x[..self.lanes],
            &self.y[..self.lanes],
            &self.z[..self.lanes],
        );
        let chunks = xs
            .chunks_exact(OWN_LANES)
            .zip(ys.chunks_exact(OWN_LANES))
            .zip(zs.chunks_exact(OWN_LANES));
        // no early exit inside a chunk, so each chunk runs as vector code
        for ((x, y), z) in chunks {
            let mut hit = 0u32;
            for l in 0..OWN_LANES {
                let (dx, dy, dz) = (x[l] - at.x, y[l] - at.y, z[l] - at.z);
                hit |= ((dx * dx + dy * dy + dz * dz) < r2) as u32;
            }
            if hit != 0 {
                return true;
            }
        }
        false
    }
}

impl<'m, 'a> Stamper<'m, 'a> {
    /// Whether the stamp is filled (see [`fill`](Self::fill)).
    pub(super) fn fills(&self) -> bool {
        self.fixed || self.target >= SMALL_TARGET
    }

    /// Fills holes after the edge pass: `cands[..kept]` are the kept
    /// candidates in face order; the darts that stay join them, each after
    /// its face's points. Returns the new count (at most the room in `cands`
    /// and `scratch`).
    ///
    /// Stamps of fewer than 256 roots are not filled: their
    /// count is a lottery over the tile's windows already, and darts would
    /// make it jump further between passes.
    pub fn fill(
        &self,
        cands: &mut [Candidate],
        kept: usize,
        scratch: &mut Scratch,
    ) -> Result<usize, Error> {
        if !self.fills() {
            return Ok(kept);
        }
        let room = cands.len().min(scratch.next.len());
        scratch.check(kept)?;
        // a dart lies within the disk radius of a cut edge, so only points
        // within twice the radius of one can clash with it: those whose
        // spacing of two radii (level LOD_LEVELS - 3) reaches past it; the
        // grid holds only those (and the darts), in a table sized for them.
        // A dart anywhere on a face the edge of buried skin crosses may
        // clash with any point: on such a mesh the grid holds them all.
        let anywhere = self.shells.has_burial_edges();
        let close = |c: &Candidate| anywhere || c.near_levels as usize >= LOD_LEVELS - 2;
        let in_grid = cands[..kept].iter().filter(|c| close(c)).count();
        let buckets = HashGrid::buckets_for(2 * in_grid + 1).min(scratch.heads.len());
        let mut grid = HashGrid::new(
            &mut scratch.heads[..buckets],
            scratch.next,
            FILL_GRID_CELL * self.radius,
        )
        .in_blocks();
        let near = &mut *scratch.near;
        let mut frame = (u32::MAX, [Vec3::ZERO; 3]);
        for (i, c) in cands[..kept].iter().enumerate() {
            if close(c) {
                if c.face != frame.0 {
                    frame = (c.face, face_frame(&self.mesh, c.face as usize));
                }
                near[i] = Near::new(c, i, &frame.1);
                grid.insert(i as u32, Vec3::from(near[i].position));
            }
        }
        let mut n = kept;
        // the face's own kept points: a run of the face-ordered candidates
        let mut own = 0;
        let mut darts = [Near::default(); RUN];
        let mut gathering = [Near::default(); RUN];
        let mut alive = [0u8; RUN];
        let mut uvs = [[0.0f32; 2]; RUN];
        let mut own_lanes = Own::new();
        let mut kept_lanes = Own::new();
        for f in 0..self.faces.len() {
            while own < kept && (cands[own].face as usize) < f {
                own += 1;
            }
            let face = &self.faces[f];
            let cut = !self.places[f].edges & 7;
            let anywhere = self.shells.burial_edge(f);
            if face.scale == 0.0 || (cut == 0 && !anywhere) {
                continue;
            }
            let own_end = own
                + cands[own..kept]
                    .iter()
                    .take_while(|c| c.face as usize == f)
                    .count();
            let r = self.local_radius(f as u32);
            let normal = Vec3::from(face.normal);
            let frame = face_frame(&self.mesh, f);
            let [a, e1, e2] = frame;
            let corners = [a, a + e1, a + e2];
            let twice_area = e1.cross(e2).length();
            let lift = super::place::BURY_LIFT * r;
            let whole_face = self.shells.face_buried(f);
            if whole_face == Some(true) {
                continue;
            }
            let first_dart = n;
            let own_points = (own..own_end)
                .filter(|&j| close(&cands[j]))
                .map(|j| near[j].position);
            let in_lanes = own_lanes.set(own_points);
            #[cfg(test)]
            POINT_BY_POINT.with(|c| c.set(c.get() + !in_lanes as usize));
            kept_lanes.set(core::iter::empty());
            // each cut edge's strip reaches `r` from the edge, or the far
            // corner; its darts are numbered on after the last edge's. A
            // face the edge of buried skin crosses takes its darts anywhere.
            let mut strips = [(0usize, 0.0f32); 3];
            let mut total = 0;
            if anywhere {
                let face_roots = 0.5 * twice_area * TILE.density() / (r * r);
                total = libm::ceilf(DARTS_PER_ROOT * face_roots) as usize;
            } else {
                for i in (0..3).filter(|&i| cut & (1 << i) != 0) {
                    let length = corners[i].distance(corners[(i + 1) % 3]);
                    let height = twice_area / length;
                    let strip_roots = length * r.min(height) * TILE.density() / (r * r);
                    total += libm::ceilf(DARTS_PER_ROOT * strip_roots) as usize;
                    strips[i] = (total, (r / height).min(1.0));
                }
            }
            for start in (0..total).step_by(RUN) {
                let m = RUN.min(total - start);
                for d in 0..m {
                    let g = start + d;
                    let key = (f as u64) << 24 | g as u64;
                    let t = rng::unit(self.seed, key, Purpose::FillDart, 0);
                    let w = rng::unit(self.seed, key, Purpose::FillDart, 1);
                    let uv = if anywhere {
                        // uniform on the face: the unit square folded onto it
                        if t + w > 1.0 {
                            [1.0 - t, 1.0 - w]
                        } else {
                            [t, w]
                        }
                    } else {
                        let i = strips.iter().position(|s| g < s.0).unwrap_or(2);
                        let (p, q, o) = (i, (i + 1) % 3, (i + 2) % 3);
                        let w = strips[i].1 * w;
                        // on the edge at t, then w of the way to the far corner
                        [0, 1].map(|k| {
                            let on = BARY[p][k] + (BARY[q][k] - BARY[p][k]) * t;
                            on + (BARY[o][k] - on) * w
                        })
                    };
                    let u = uv[0].clamp(0.0, 1.0);
                    uvs[d] = [u, uv[1].clamp(0.0, 1.0 - u)];
                    darts[d] = Near::new(&dart(f, uvs[d]), 0, &frame);
                }
                // this face's kept points are tested first, and only the
                // darts they leave gather the points of other faces
                let r2 = r * r;
                let clash = |near: &[Near], j: usize, at: Vec3| {
                    Vec3::from(near[j].position).distance_squared(at) < r2
                };
                // the darts the face kept in earlier runs: the same test the
                // last stage makes, made before the gathering
                let kept_clash =
                    |kept_lanes: &Own, near: &[Near], n: usize, at: Vec3| match kept_lanes.whole {
                        true => kept_lanes.clashes(at, r2),
                        false => (first_dart..n).any(|j| clash(near, j, at)),
                    };
                let mut left = 0;
                for (d, dart) in darts[..m].iter().enumerate() {
                    let at = Vec3::from(dart.position);
                    let blocked = match in_lanes {
                        true => own_lanes.clashes(at, r2),
                        false => (own..own_end).any(|j| close(&cands[j]) && clash(near, j, at)),
                    } || (n > first_dart && kept_clash(&kept_lanes, near, n, at));
                    alive[left] = d as u8;
                    left += !blocked as usize;
                }
                if left == 0 {
                    continue;
                }
                for (k, &d) in alive[..left].iter().enumerate() {
                    gathering[k] = darts[d as usize];
                }
                let group = &gathering[..left];
                let mut clashed = [false; RUN];
                let buf = &mut scratch.gathered;
                Self::gather(&grid, near, group, r * 1.0001, buf, |buf| {
                    // the dart's own radius, which the pair's (that of the
                    // denser side) never exceeds: a dart does not crowd a
                    // sparse face next to a dense one
                    self.weigh(buf, f as u32, |_| r * r);
                    for (hit, q) in clashed.iter_mut().zip(group) {
                        *hit = *hit || buf.clashes(q.position);
                    }
                });
                // the gathered points are other faces' only: this face's
                // darts are tested here
                for (k, &d) in alive[..left].iter().enumerate() {
                    let d = d as usize;
                    let at = Vec3::from(group[k].position);
                    if clashed[k]
                        || n == room
                        || kept_clash(&kept_lanes, near, n, at)
                        || (whole_face.is_none() && self.shells.buried(at, normal, lift))
                    {
                        continue;
                    }
                    kept_lanes.push(group[k].position);
                    cands[n] = dart(f, uvs[d]);
                    near[n] = Near {
                        index: n as u32,
                        ..group[k]
                    };
                    grid.insert(n as u32, at);
                    n += 1;
                }
            }
        }
        // the darts go among the kept points, after those of their face, so
        // the candidates (and the roots) stay in face order; the records'
        // memory is free now and holds the darts meanwhile
        let darts = n - kept;
        let held: &mut [Candidate] = bytemuck::cast_slice_mut(
            &mut bytemuck::cast_slice_mut::<Near, u8>(near)
                [..darts * core::mem::size_of::<Candidate>()],
        );
        held.copy_from_slice(&cands[kept..n]);
        let (mut i, mut j) = (kept, darts);
        for w in (0..n).rev() {
            if j == 0 {
                break;
            }
            if i > 0 && cands[i - 1].face > held[j - 1].face {
                cands[w] = cands[i - 1];
                i -= 1;
            } else {
                cands[w] = held[j - 1];
                j -= 1;
            }
        }
        Ok(n)
    }
}
