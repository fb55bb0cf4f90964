//! The candidates near a face's boundary as small records, and the buffer
//! the edge and LOD passes gather them in for vector tests.

use super::{Candidate, Stamper, SAME_AIR_DOT};
use crate::arena::{Arena, ArenaLayout};
use crate::surface::grid::HashGrid;
use crate::Error;
use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};

/// Points of other faces one group of tests holds at once; a face with more
/// neighbours is tested in chunks (unit tests use a tiny buffer so that every
/// stamp they run takes that path).
#[cfg(not(test))]
pub(super) const GATHER: usize = 1024;
#[cfg(test)]
pub(super) const GATHER: usize = 7;

/// A candidate near its triangle's boundary, copied out of the candidate
/// list so the edge and LOD passes walk small records, one face at a time.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub(super) struct Near {
    pub(super) position: [f32; 3],
    pub(super) face: u32,
    /// [`Candidate::near_levels`].
    pub(super) near_levels: u32,
    /// Index in the candidate list.
    pub(super) index: u32,
}

impl Near {
    /// The position, and the face's bits in the fourth lane, in one load.
    #[inline]
    fn head(&self) -> Vec4 {
        let bytes = &bytemuck::bytes_of(self)[..16];
        Vec4::from_array(bytemuck::pod_read_unaligned(bytes))
    }

    /// The record of candidate `c`, at `index`, on a face of frame `frame`
    /// (see [`face_frame`](super::face_frame)).
    #[inline]
    pub(super) fn new(c: &Candidate, index: usize, [a, e1, e2]: &[Vec3; 3]) -> Self {
        Near {
            position: (*a + *e1 * c.uv[0] + *e2 * c.uv[1]).into(),
            face: c.face,
            near_levels: c.near_levels as u32,
            index: index as u32,
        }
    }
}

/// The points of other faces one face's points are tested against, with
/// each one's squared clash distance (edge pass) or weight (LOD pass), as
/// flat arrays so the tests run as a vector loop over contiguous memory.
pub(super) struct Gathered<'a> {
    x: &'a mut [f32],
    y: &'a mut [f32],
    z: &'a mut [f32],
    r2: &'a mut [f32],
    pub(super) face: &'a mut [u32],
    len: usize,
}

/// Lanes of the clash test; the gathered arrays are padded to a multiple.
pub(super) const LANES: usize = 8;
/// Slots of each gathered array: [`GATHER`] rounded up to whole lanes.
pub(super) const GATHER_SLOTS: usize = GATHER.div_ceil(LANES) * LANES;

impl<'a> Gathered<'a> {
    /// Adds the bytes [`Gathered::new`] takes to `layout`.
    pub(super) fn layout(layout: &mut ArenaLayout) {
        layout.add::<f32>(4 * GATHER_SLOTS).add::<u32>(GATHER_SLOTS);
    }

    pub(super) fn new(arena: &mut Arena<'a>) -> Result<Self, Error> {
        let all = arena.alloc::<f32>(4 * GATHER_SLOTS)?;
        let (x, rest) = all.split_at_mut(GATHER_SLOTS);
        let (y, rest) = rest.split_at_mut(GATHER_SLOTS);
        let (z, r2) = rest.split_at_mut(GATHER_SLOTS);
        Ok(Gathered {
            x,
            y,
            z,
            r2,
            face: arena.alloc::<u32>(GATHER_SLOTS)?,
            len: 0,
        })
    }

    /// Writes a point of face `face` in the slot after the last (not full),
    /// without taking it: the caller advances `len` to keep it.
    #[inline]
    fn set(&mut self, p: [f32; 3], face: u32) {
        let i = self.len;
        (self.x[i], self.y[i], self.z[i], self.face[i]) = (p[0], p[1], p[2], face);
    }

    /// Moves gathered point `i` out of reach of every point.
    #[inline]
    fn remove(&mut self, i: usize) {
        self.x[i] = f32::INFINITY;
    }

    /// Fills the slots past `len` up to whole lanes with points out of
    /// reach (at infinity, with a clash distance and a weight of 1), so the
    /// tests run on whole lanes only.
    #[inline]
    fn pad(&mut self) {
        let (len, end) = (self.len, self.len.div_ceil(LANES) * LANES);
        for a in [&mut *self.x, &mut *self.y, &mut *self.z] {
            a[len..end].fill(f32::INFINITY);
        }
        self.r2[len..end].fill(1.0);
    }

    /// The gathered coordinates and values, in whole lanes (after
    /// [`pad`](Self::pad)).
    #[inline]
    fn lanes(&self) -> impl Iterator<Item = (&[f32], &[f32], &[f32], &[f32])> {
        let n = self.len.div_ceil(LANES) * LANES;
        let (xs, ys, zs, rs) = (&self.x[..n], &self.y[..n], &self.z[..n], &self.r2[..n]);
        xs.chunks_exact(LANES)
            .zip(ys.chunks_exact(LANES))
            .zip(zs.chunks_exact(LANES).zip(rs.chunks_exact(LANES)))
            .map(|((x, y), (z, r))| (x, y, z, r))
    }

    /// Whether `p` is closer to a gathered point than its clash distance.
    #[inline]
    pub(super) fn clashes(&self, p: [f32; 3]) -> bool {
        // no early exit inside a chunk, so each chunk runs as vector code
        self.lanes().any(|(x, y, z, r)| {
            let mut hit = 0u32;
            for l in 0..LANES {
                let (dx, dy, dz) = (x[l] - p[0], y[l] - p[1], z[l] - p[2]);
                hit |= ((dx * dx + dy * dy + dz * dz) < r[l]) as u32;
            }
            hit != 0
        })
    }

    /// The smallest squared distance from `p` to a gathered point, times
    /// that point's weight (infinite when none is in reach).
    #[inline]
    pub(super) fn nearest(&self, p: [f32; 3]) -> f32 {
        let mut best = [f32::INFINITY; LANES];
        for (x, y, z, w) in self.lanes() {
            for l in 0..LANES {
                let (dx, dy, dz) = (x[l] - p[0], y[l] - p[1], z[l] - p[2]);
                let d = (dx * dx + dy * dy + dz * dz) * w[l];
                // a select, not f32::min: it maps to one vector instruction
                best[l] = if d < best[l] { d } else { best[l] };
            }
        }
        best.into_iter().fold(f32::INFINITY, f32::min)
    }
}

impl<'m, 'a> Stamper<'m, 'a> {
    /// Gathers into `buf` the points of `grid` (indices into `records`) that
    /// lie in the box around `group` (points of one face) widened by
    /// `reach` and belong to another face, and calls `test` each time `buf`
    /// is full and once at the end if it holds any.
    ///
    /// The grid is walked once for the whole group, where a walk per point
    /// would visit the same buckets again and again; `test` then runs the
    /// group against the gathered points in a vector loop.
    pub(super) fn gather(
        grid: &HashGrid,
        records: &[Near],
        group: &[Near],
        reach: f32,
        buf: &mut Gathered,
        mut test: impl FnMut(&mut Gathered),
    ) {
        let at = |q: &Near| Vec3::from(q.position);
        let (lo, hi) = group
            .iter()
            .fold((at(&group[0]), at(&group[0])), |(lo, hi), q| {
                (lo.min(at(q)), hi.max(at(q)))
            });
        let (lo, hi) = (lo - Vec3::splat(reach), hi + Vec3::splat(reach));
        // the box test reads a record's position and face as one vector and
        // looks at the first three lanes
        let (lo4, hi4) = (lo.extend(0.0), hi.extend(0.0));
        let f = group[0].face;
        buf.len = 0;
        for i in grid.in_box(lo, hi) {
            if buf.len == GATHER {
                test(buf);
                buf.len = 0;
            }
            let o = &records[i as usize];
            let p = o.head();
            // every point is written and only those of other faces in the box
            // kept: branches on these tests would mispredict
            let inside = (p.cmpge(lo4) & p.cmple(hi4)).bitmask() & 7 == 7;
            let keep = (o.face != f) & inside;
            buf.set(o.position, o.face);
            buf.len += keep as usize;
        }
        if buf.len > 0 {
            test(buf);
        }
    }

    /// Sets the value of each gathered point to `value` of the larger
    /// density scale of its face and face `f`, removes the points that do
    /// not face the same air as face `f` (see [`same_air`](super::same_air):
    /// the two sides of an ear never clash; tested on the gathered point
    /// and on `f`'s corners), and pads the lanes.
    pub(super) fn weigh(&self, buf: &mut Gathered, f: u32, value: impl Fn(f32) -> f32) {
        let face = &self.faces[f as usize];
        let normal = Vec3::from(face.normal);
        let corners = self.mesh.corners(f as usize);
        let here = corners[0];
        // gathered points come in runs of one face: its value is reused, and
        // whether some point of face `f` lies strictly in front of its
        // plane (a corner of `f` does, if any point does; corners the
        // faces share lie on both planes and leave a knife edge's two
        // sides apart)
        let (mut last, mut last_value) = (u32::MAX, 0.0);
        let (mut facing, mut seen) = (true, false);
        for i in 0..buf.len {
            let o = buf.face[i];
            if o != last {
                let other = &self.faces[o as usize];
                let m = Vec3::from(other.normal);
                facing = m.dot(normal) > SAME_AIR_DOT;
                seen = !facing && {
                    let at = self.mesh.corners(o as usize)[0];
                    corners.iter().any(|&q| (q - at).dot(m) > 0.0)
                };
                (last, last_value) = (o, value(other.scale.max(face.scale)));
            }
            buf.r2[i] = last_value;
            // across a concave crease: the point in front of this face's
            // plane, and this face partly in front of its own
            let ahead = seen && (Vec3::new(buf.x[i], buf.y[i], buf.z[i]) - here).dot(normal) > 0.0;
            if !(facing || ahead) {
                buf.remove(i);
            }
        }
        buf.pad();
    }
}
