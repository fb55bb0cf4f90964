//! Placing triangles in the tile: where each face lies in it, and the
//! tile points a face takes, as candidates.

use super::near::LANES;
use super::{Candidate, Stamper};
use crate::rng::{self, Purpose};
use crate::stamp::chart::Unfolded;
use crate::stamp::tile::{CELL, CELLS, LEVEL_STEPS, LOD_LEVELS, TILE, TILE_SIDE};
use crate::surface::grid::floor_i32;
use crate::{Error, Mesh};
use bytemuck::{Pod, Zeroable};
use core::ops::Range;
use glam::{BVec4A, Vec2, Vec4};

/// Where a face lies in the tile, computed once for every pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(super) struct TilePlace {
    /// Corners in the chart's plane, turned by the chart's rotation (world
    /// units times the face's scale; a pass divides by the radius). Faces
    /// linked across an edge hold bit-identical copies of its two corners.
    corners: [[f32; 2]; 3],
    /// For each linked edge, the neighbour's third corner, turned the same way.
    across: [[f32; 2]; 3],
    /// Where the chart's plane origin lands in the tile (tile units).
    pub(super) offset: [f32; 2],
    /// The chart's rotation (cosine, sine).
    rot: [f32; 2],
    /// [`Unfolded::edges`], and in bit `6 + i` whether edge `i` runs from
    /// the lower vertex index to the higher.
    pub(super) edges: u32,
}

/// A chart's random rotation and offset in the tile.
#[derive(Clone, Copy)]
pub(super) struct ChartFrame {
    rot: Vec2,
    pub(super) offset: Vec2,
}

impl ChartFrame {
    /// The frame of the chart whose first face is `chart`.
    pub(super) fn new(seed: u64, chart: usize) -> Self {
        let id = chart as u64;
        let angle = rng::unit(seed, id, Purpose::StampRotation, 0) * core::f32::consts::TAU;
        ChartFrame {
            rot: Vec2::new(libm::cosf(angle), libm::sinf(angle)),
            offset: Vec2::new(
                rng::unit(seed, id, Purpose::StampOffsetX, 0),
                rng::unit(seed, id, Purpose::StampOffsetY, 0),
            ) * TILE_SIDE as f32,
        }
    }
}

impl TilePlace {
    pub(super) fn new(mesh: &Mesh, f: usize, laid: &Unfolded, frame: ChartFrame) -> Self {
        let turn = |p: [f32; 2]| frame.rot.rotate(Vec2::from(p)).into();
        let v = mesh.triangles.get(f);
        let forward = (0..3).fold(0, |e, i| e | ((v[i] < v[(i + 1) % 3]) as u32) << (6 + i));
        TilePlace {
            corners: laid.corners.map(turn),
            across: laid.across.map(turn),
            offset: frame.offset.into(),
            rot: frame.rot.into(),
            edges: laid.edges | forward,
        }
    }

    /// The frame of this face's chart.
    pub(super) fn frame(&self) -> ChartFrame {
        ChartFrame {
            rot: Vec2::from(self.rot),
            offset: Vec2::from(self.offset),
        }
    }

    /// Edge `i` (corner `i` to corner `i + 1`) in the chart's plane.
    pub(super) fn edge(&self, i: usize) -> Vec2 {
        Vec2::from(self.corners[(i + 1) % 3]) - Vec2::from(self.corners[i])
    }
}

/// The x extent of triangle `t` within the strip y0 <= y <= y1, if any.
#[inline]
pub(super) fn row_span(t: &[Vec2; 3], y0: f32, y1: f32) -> Option<(f32, f32)> {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for (i, a) in t.iter().enumerate() {
        if (y0..=y1).contains(&a.y) {
            (lo, hi) = (lo.min(a.x), hi.max(a.x));
        }
        let b = t[(i + 1) % 3];
        for y in [y0, y1] {
            if (a.y - y) * (b.y - y) < 0.0 {
                let x = a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y);
                (lo, hi) = (lo.min(x), hi.max(x));
            }
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// How far off the skin the buried test looks, in local disk radii.
pub(super) const BURY_LIFT: f32 = 1e-3;

/// Tile points a face collects before they become candidates: the inside
/// test runs on every tile point the face covers, the rest only on the
/// points inside, a batch at a time, as vector code.
pub(super) const BATCH: usize = 128;

/// Tile points found inside one face, waiting to become candidates.
pub(super) struct Batch {
    x: [f32; BATCH],
    y: [f32; BATCH],
    pub(super) level: [u8; BATCH],
    order: [u8; BATCH],
    len: usize,
}

impl Default for Batch {
    fn default() -> Self {
        Batch {
            x: [0.0; BATCH],
            y: [0.0; BATCH],
            level: [0; BATCH],
            order: [0; BATCH],
            len: 0,
        }
    }
}

/// One face at one radius, in tile units: what placing its tile points needs.
pub(super) struct Placing {
    corners: [Vec2; 3],
    /// `[x, y, c]`: twice the signed area a point `p` makes with edge `e`
    /// is `x[e] * p.y - y[e] * p.x - c[e]`, the edge taken from its
    /// lower-numbered vertex and negated (exactly) when the face runs it the
    /// other way. The two faces on a linked edge compute the same area bit
    /// for bit, so a tile point on it goes to exactly one. Lanes are edges,
    /// so a point's three tests run as one vector operation; the fourth
    /// lane always passes.
    cross: [Vec4; 3],
    /// Whether the face takes the points exactly on edge `e` (when it runs
    /// the edge from its lower vertex); the fourth lane is unused.
    ties: BVec4A,
    inv_len: [f32; 3],
    inv_det: f32,
    /// Whether edge `e` is linked (not cut).
    linked: [bool; 3],
    /// The far edges of each linked neighbour (from either end of the
    /// shared edge to its third corner): start, unit direction, length.
    far_from: [Vec2; 6],
    far_dir: [Vec2; 6],
    far_len: [f32; 6],
}

impl Placing {
    #[inline]
    pub(super) fn new(face: &TilePlace, k: f32) -> Self {
        let offset = Vec2::from(face.offset);
        let at = |p: [f32; 2]| offset + Vec2::from(p) * k;
        let corners = face.corners.map(at);
        let mut place = Placing {
            corners,
            cross: [Vec4::ZERO; 3],
            ties: BVec4A::FALSE,
            inv_len: [0.0; 3],
            inv_det: 1.0 / (corners[1] - corners[0]).perp_dot(corners[2] - corners[0]),
            linked: [false; 3],
            far_from: [Vec2::ZERO; 6],
            far_dir: [Vec2::ZERO; 6],
            far_len: [0.0; 6],
        };
        // built as arrays (writing a vector's lanes one by one is slower);
        // the fourth lane's area is 1, so it always passes
        let (mut cross, mut ties) = ([[0.0; 4], [0.0; 4], [0.0, 0.0, 0.0, -1.0]], [false; 3]);
        for i in 0..3 {
            let (p, q) = (corners[i], corners[(i + 1) % 3]);
            let forward = face.edges & (64 << i) != 0;
            let (from, to) = if forward { (p, q) } else { (q, p) };
            let (dir, sign) = (to - from, if forward { 1.0 } else { -1.0 });
            cross[0][i] = sign * dir.x;
            cross[1][i] = sign * dir.y;
            cross[2][i] = sign * dir.perp_dot(from);
            ties[i] = forward;
            place.inv_len[i] = 1.0 / (q - p).length();
            if face.edges & (1 << i) != 0 {
                place.linked[i] = true;
                let w = at(face.across[i]);
                for (s, end) in [(2 * i, p), (2 * i + 1, q)] {
                    let d = w - end;
                    place.far_from[s] = end;
                    place.far_len[s] = d.length();
                    place.far_dir[s] = d / place.far_len[s];
                }
            }
        }
        place.cross = cross.map(Vec4::from_array);
        place.ties = BVec4A::new(ties[0], ties[1], ties[2], false);
        place
    }

    /// [`cross`](Self::cross) as arrays, for code that reads it by edge
    /// (a vector read by a varying lane is slower).
    #[inline]
    fn cross_by_edge(&self) -> [[f32; 4]; 3] {
        self.cross.map(<[f32; 4]>::from)
    }

    /// Adds tile point `p` to `batch` when it lies inside the face (the
    /// slot is written either way: a branch would mispredict about every
    /// other point). `batch` must have room.
    #[inline]
    fn test(&self, batch: &mut Batch, p: Vec2, level: u8, order: u8) {
        let [cx, cy, cc] = self.cross;
        // the same operations in the same order as `emit`'s barycentrics,
        // so the same bits
        let s = cx * Vec4::splat(p.y) - cy * Vec4::splat(p.x) - cc;
        let inside = (s.cmpgt(Vec4::ZERO) | (s.cmpeq(Vec4::ZERO) & self.ties)).all();
        // the caller keeps len below BATCH; the mask spares the bounds checks
        let i = batch.len & (BATCH - 1);
        (batch.x[i], batch.y[i], batch.level[i]) = (p.x, p.y, level);
        batch.order[i] = order;
        batch.len += inside as usize;
    }

    /// Writes the points of `batch` to `out` from slot `n` as candidates of
    /// face `f` and empties the batch; returns the new count.
    fn emit(
        &self,
        batch: &mut Batch,
        f: u32,
        squares: &[f32; LOD_LEVELS],
        out: &mut [Candidate],
        n: usize,
    ) -> Result<usize, Error> {
        let len = batch.len;
        batch.len = 0;
        let available = out.len();
        let out = out.get_mut(n..n + len).ok_or(Error::OutputTooSmall {
            needed: n + len,
            available,
        })?;
        let mut near = [0u8; BATCH];
        let lanes = len.div_ceil(LANES) * LANES;
        self.near_levels(&batch.x[..lanes], &batch.y[..lanes], squares, &mut near);
        let [cx, cy, cc] = self.cross_by_edge();
        for (i, c) in out.iter_mut().enumerate() {
            let (x, y) = (batch.x[i], batch.y[i]);
            // twice the signed area with edge e
            let area = |e: usize| cx[e] * y - cy[e] * x - cc[e];
            let (u, v) = (area(2) * self.inv_det, area(0) * self.inv_det);
            // a point inside by the edge tests can still round a hair
            // outside in barycentrics; u + v then sums to at most 1 in f32
            let u = u.clamp(0.0, 1.0);
            let v = v.clamp(0.0, 1.0 - u);
            *c = Candidate {
                face: f,
                uv: [u, v],
                level: batch.level[i] / LEVEL_STEPS as u8,
                step: batch.level[i] % LEVEL_STEPS as u8,
                order: batch.order[i],
                near_levels: near[i],
            };
        }
        Ok(n + len)
    }

    /// [`Candidate::near_levels`] of tile points `(xs, ys)` (whole lanes),
    /// from the smallest disk around each that crosses a cut edge, or the
    /// far side of a linked neighbour (up to there, every point comes from
    /// one piece of the stamp), and the squared spacings of the levels.
    pub(super) fn near_levels(
        &self,
        xs: &[f32],
        ys: &[f32],
        squares: &[f32; LOD_LEVELS],
        out: &mut [u8],
    ) {
        let [cross_x, cross_y, cross_c] = self.cross_by_edge();
        let lanes = xs.chunks_exact(LANES).zip(ys.chunks_exact(LANES));
        for ((x, y), d) in lanes.zip(out.chunks_exact_mut(LANES)) {
            let mut best = [f32::INFINITY; LANES];
            for e in 0..3 {
                let (cx, cy, cc) = (cross_x[e], cross_y[e], cross_c[e]);
                let inv_len = self.inv_len[e];
                let mut term = [0.0; LANES];
                for l in 0..LANES {
                    let line = (cx * y[l] - cy * x[l] - cc) * inv_len;
                    term[l] = line * line;
                }
                // past a linked edge, the disk must also reach the far side
                // of the neighbour (a cut edge needs no more: one branch per
                // edge, the same for every point of the face)
                if self.linked[e] {
                    let mut far = [f32::INFINITY; LANES];
                    for s in [2 * e, 2 * e + 1] {
                        let (fx, fy) = (self.far_from[s].x, self.far_from[s].y);
                        let (ux, uy, len) = (self.far_dir[s].x, self.far_dir[s].y, self.far_len[s]);
                        for l in 0..LANES {
                            let (dx, dy) = (x[l] - fx, y[l] - fy);
                            let t = dx * ux + dy * uy;
                            let c = if t < 0.0 { 0.0 } else { t };
                            let c = if c > len { len } else { c };
                            let d2 = dx * dx + dy * dy - c * (2.0 * t - c);
                            far[l] = if d2 < far[l] { d2 } else { far[l] };
                        }
                    }
                    for l in 0..LANES {
                        term[l] = if far[l] > term[l] { far[l] } else { term[l] };
                    }
                }
                for l in 0..LANES {
                    best[l] = if term[l] < best[l] { term[l] } else { best[l] };
                }
            }
            let mut near = [0u8; LANES];
            for &s2 in squares {
                for l in 0..LANES {
                    near[l] += (best[l] < s2) as u8;
                }
            }
            d.copy_from_slice(&near);
        }
    }
}

impl<'m, 'a> Stamper<'m, 'a> {
    /// Stamps the triangles in `faces` at the current radius into `out`, in
    /// face order; returns how many were written. Slots past that count may
    /// be overwritten too. Pure: safe to run disjoint ranges on different
    /// threads.
    pub fn stamp_faces(&self, faces: Range<usize>, out: &mut [Candidate]) -> Result<usize, Error> {
        let squares = self.spacings.map(|s| s * s);
        // made once: clearing a batch per face costs more than its tests
        let mut batch = Batch::default();
        let mut n = 0;
        for f in faces {
            if self.faces[f].scale == 0.0 {
                continue;
            }
            let first = n;
            n = self.stamp_face(f, &squares, &mut batch, out, n)?;
            n = self.near_shells(f, &mut out[..n], first);
        }
        Ok(n)
    }

    /// Applies [`Shells`](super::shell::Shells) to face `f`'s candidates,
    /// `out[first..]`: near another shell they take part in the edge pass
    /// and every LOD level; buried ones are dropped. Returns the new count.
    fn near_shells(&self, f: usize, out: &mut [Candidate], first: usize) -> usize {
        let shells = &self.shells;
        if shells.near_other(f) {
            for c in &mut out[first..] {
                c.near_levels = LOD_LEVELS as u8;
            }
        }
        let lift = BURY_LIFT * self.local_radius(f as u32);
        match shells.face_buried(f) {
            Some(false) => return out.len(),
            Some(true) => return first,
            None => {}
        }
        let [a, e1, e2] = super::face_frame(&self.mesh, f);
        let normal = glam::Vec3::from(self.faces[f].normal);
        let mut n = first;
        for i in first..out.len() {
            let c = out[i];
            let p = a + e1 * c.uv[0] + e2 * c.uv[1];
            out[n] = c;
            n += !shells.buried(p, normal, lift) as usize;
        }
        n
    }

    /// Stamps triangle `f` into `out` from slot `n` (`squares`: the squared
    /// LOD spacings; `batch`: empty, and left empty); returns the new count.
    fn stamp_face(
        &self,
        f: usize,
        squares: &[f32; LOD_LEVELS],
        batch: &mut Batch,
        out: &mut [Candidate],
        mut n: usize,
    ) -> Result<usize, Error> {
        let place = Placing::new(&self.places[f], 1.0 / self.radius);
        let corners = place.corners;
        let lo_y = corners[0].y.min(corners[1].y).min(corners[2].y);
        let hi_y = corners[0].y.max(corners[1].y).max(corners[2].y);
        let (side, cell) = (CELLS as i32, CELL as f32);
        let inv = 1.0 / cell;
        for cy in floor_i32(lo_y * inv)..=floor_i32(hi_y * inv) {
            let wy = cy.rem_euclid(side);
            let shift_y = (cy - wy) as f32 * cell;
            // only the cells the triangle crosses in this row, not its bounding box
            let y0 = cy as f32 * cell;
            let Some((x0, x1)) = row_span(&corners, y0, y0 + cell) else {
                continue;
            };
            let (mut cx, last) = (floor_i32(x0 * inv), floor_i32(x1 * inv));
            while cx <= last {
                // the cells up to the tile's edge are one run of points
                let wx = cx.rem_euclid(side);
                let len = (side - wx).min(last - cx + 1);
                let shift = Vec2::new((cx - wx) as f32 * cell, shift_y);
                let (points, levels, orders) = TILE.run(wx as usize, wy as usize, len as usize);
                for ((&p, &level), &order) in points.iter().zip(levels).zip(orders) {
                    if batch.len == BATCH {
                        n = place.emit(batch, f as u32, squares, out, n)?;
                    }
                    place.test(batch, Vec2::from(p) + shift, level, order);
                }
                cx += len;
            }
        }
        place.emit(batch, f as u32, squares, out, n)
    }
}
