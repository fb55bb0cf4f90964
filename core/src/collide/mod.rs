//! Colliders and the push-out (paper 3.3): a posed guide with a point
//! inside a collider is rotated rigidly about its root, toward its normal,
//! by the smallest tried angle that frees every point (the rotation and the
//! search are shared with settle: `lift`). Colliders are shared geometry:
//! the guide dynamics, the render strands' push-out and trimming all use them.
//!
//! Colliders: spheres, capsules and half-spaces (planes) given per step, the
//! deforming body itself (its inside test), and a host's signed distance
//! field (a level set, a cloth's distance: anything that answers distances).

pub(crate) mod lift;

use crate::curve::{cut, WHOLE};
use crate::surface::body::Body;
use crate::surface::frame::Frame;
use crate::surface::mesh::MAX_COORDINATE;
use crate::Error;
use bytemuck::{Pod, Zeroable};
use core::f32::consts::FRAC_PI_2;
use glam::{Vec2, Vec3, Vec3A};
use lift::{first_clear, none_inside, toward_normal, Turn, LIFT_STEP, LIFT_STEPS};

/// Cells per triangle of the body grid built per frame for collisions, by a
/// step or for a frame's colliders (see
/// [`BodyPlan::with_density`](crate::surface::body::BodyPlan::with_density)):
/// a step's few hundred thousand guide points do not repay the default
/// grid's build. Both build it alike, so a step colliding with either body
/// gives the same bits; the frame's body thus answers the render strands'
/// push-out at this density too (a query there costs ~1.4x what it would
/// at the default's, its build ~0.6x).
pub const COLLISION_CELLS_PER_TRIANGLE: f32 = 8.0;

/// A solid sphere.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Sphere {
    /// Centre.
    pub centre: [f32; 3],
    /// Radius (>= 0).
    pub radius: f32,
}

/// A solid capsule: the points within `radius` of the segment `a`-`b`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Capsule {
    /// One end of the axis.
    pub a: [f32; 3],
    /// The other end.
    pub b: [f32; 3],
    /// Radius (>= 0).
    pub radius: f32,
}

/// A solid half-space: the points `p` with `dot(normal, p) < offset`
/// (`normal` need not be unit length; the test uses it as given).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Plane {
    /// Outward normal (not zero).
    pub normal: [f32; 3],
    /// `dot(normal, p)` on the surface.
    pub offset: f32,
}

/// A host's signed distance field: negative inside. Called from the
/// threads a step runs on, with a guide's points at a time.
pub trait SignedDistance: Sync {
    /// Writes the signed distance of each of `points` (x, y, z) to `out`
    /// (as long).
    fn distances(&self, points: &[[f32; 3]], out: &mut [f32]);
}

/// Everything the guides collide with in one step.
#[derive(Clone, Copy, Default)]
pub struct Colliders<'r> {
    /// Spheres.
    pub spheres: &'r [Sphere],
    /// Capsules.
    pub capsules: &'r [Capsule],
    /// Half-spaces.
    pub planes: &'r [Plane],
    /// The deforming body (built on this step's mesh), or none.
    pub body: Option<&'r Body<'r>>,
    /// A host's signed distance field, or none.
    pub field: Option<&'r dyn SignedDistance>,
}

impl Colliders<'_> {
    /// Checks that every shape is finite, within the coordinate range, with
    /// radii >= 0 and planes with a normal.
    pub fn check(&self) -> Result<(), Error> {
        let finite = |v: &[f32]| v.iter().all(|c| c.is_finite());
        let shapes = [
            (
                "spheres",
                self.spheres
                    .iter()
                    .map(|s| finite(&s.centre) && finite(&[s.radius]))
                    .position(|f| !f),
            ),
            (
                "capsules",
                self.capsules
                    .iter()
                    .map(|c| finite(&c.a) && finite(&c.b) && finite(&[c.radius]))
                    .position(|f| !f),
            ),
            (
                "planes",
                self.planes
                    .iter()
                    .map(|p| finite(&p.normal) && finite(&[p.offset]))
                    .position(|f| !f),
            ),
        ];
        if let Some((what, Some(index))) = shapes.into_iter().find(|(_, at)| at.is_some()) {
            return Err(Error::NonFinite { what, index });
        }
        let fine = |v: &[f32]| v.iter().all(|c| c.abs() <= MAX_COORDINATE);
        for (i, s) in self.spheres.iter().enumerate() {
            if !(fine(&s.centre) && fine(&[s.radius]) && s.radius >= 0.0) {
                return Err(Error::OutOfDomain {
                    what: "spheres (within 1e9, radius >= 0)",
                    index: i,
                });
            }
        }
        for (i, c) in self.capsules.iter().enumerate() {
            if !(fine(&c.a) && fine(&c.b) && fine(&[c.radius]) && c.radius >= 0.0) {
                return Err(Error::OutOfDomain {
                    what: "capsules (within 1e9, radius >= 0)",
                    index: i,
                });
            }
        }
        for (i, p) in self.planes.iter().enumerate() {
            if !(fine(&p.normal) && fine(&[p.offset]) && Vec3::from(p.normal) != Vec3::ZERO) {
                return Err(Error::OutOfDomain {
                    what: "planes (within 1e9, normal not zero)",
                    index: i,
                });
            }
        }
        Ok(())
    }
}

/// Distance from `p` to the segment `a`-`b`.
fn segment_distance(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

/// The shapes of `Colliders` that a strand of `reach` rooted at `root` can
/// touch, and the body and field (which are asked per point).
pub(crate) struct Near<'c, 'r> {
    all: &'c Colliders<'r>,
    spheres: [u32; MAX_NEAR],
    capsules: [u32; MAX_NEAR],
    planes: [u32; MAX_NEAR],
    counts: [usize; 3],
}

/// Most shapes of each kind kept per strand; when more of a kind are
/// near, the strand is tested against every shape of that kind. Few: the
/// lists are made (and zeroed) for every strand.
const MAX_NEAR: usize = 16;

impl<'c, 'r> Near<'c, 'r> {
    pub(crate) fn new(all: &'c Colliders<'r>, root: Vec3, reach: f32) -> Self {
        let mut near = Near {
            all,
            spheres: [0; MAX_NEAR],
            capsules: [0; MAX_NEAR],
            planes: [0; MAX_NEAR],
            counts: [0; 3],
        };
        // the shapes of each kind near the root; past MAX_NEAR the count
        // still grows, and every shape of that kind is tested
        fn keep(list: &mut [u32; MAX_NEAR], count: &mut usize, i: usize) {
            if *count < MAX_NEAR {
                list[*count] = i as u32;
            }
            *count += 1;
        }
        for (i, s) in all.spheres.iter().enumerate() {
            if Vec3::from(s.centre).distance(root) < s.radius + reach {
                keep(&mut near.spheres, &mut near.counts[0], i);
            }
        }
        // outside a capsule's axis box widened by `within` and by more
        // than the rounding of the distance (per axis: a few units in the
        // last place of the largest coordinate there, a floor where the
        // squares underflow), the distance could only say farther: most
        // capsules of a creature are, and skip its division and root
        let root4 = Vec3A::from(root);
        for (i, c) in all.capsules.iter().enumerate() {
            let (a, b, within) = (Vec3A::from(c.a), Vec3A::from(c.b), c.radius + reach);
            let (lo, hi) = (a.min(b), a.max(b));
            let size = lo.abs().max(hi.abs()).max(root4.abs());
            let wide = Vec3A::splat(within * (1.0 + 1e-4) + 1e-18) + size * (8.0 * f32::EPSILON);
            let boxed = root4.cmpge(lo - wide).all() && root4.cmple(hi + wide).all();
            if boxed && segment_distance(root, a.into(), b.into()) < within {
                keep(&mut near.capsules, &mut near.counts[1], i);
            }
        }
        for (i, p) in all.planes.iter().enumerate() {
            let n = Vec3::from(p.normal);
            if n.dot(root) - p.offset < reach * n.length() {
                keep(&mut near.planes, &mut near.counts[2], i);
            }
        }
        near
    }

    /// The indices of kind `kind` to test: those kept, or all `total`
    /// when more were near than kept.
    fn shapes<'s>(&self, kind: usize, kept: &'s [u32; MAX_NEAR], total: usize) -> Shapes<'s> {
        if self.counts[kind] > MAX_NEAR {
            Shapes::All(0..total)
        } else {
            Shapes::Kept(kept[..self.counts[kind]].iter())
        }
    }

    /// True when nothing can touch the strand.
    pub(crate) fn is_empty(&self) -> bool {
        self.counts == [0; 3] && self.all.body.is_none() && self.all.field.is_none()
    }

    /// True when `p` is inside a sphere, a capsule, a half-space or the body.
    pub(crate) fn in_shape(&self, p: Vec3) -> bool {
        let all = self.all;
        self.shapes(0, &self.spheres, all.spheres.len()).any(|i| {
            let s = &all.spheres[i];
            p.distance(Vec3::from(s.centre)) < s.radius
        }) || self.shapes(1, &self.capsules, all.capsules.len()).any(|i| {
            let c = &all.capsules[i];
            segment_distance(p, c.a.into(), c.b.into()) < c.radius
        }) || self.shapes(2, &self.planes, all.planes.len()).any(|i| {
            let s = &all.planes[i];
            Vec3::from(s.normal).dot(p) < s.offset
        }) || all.body.is_some_and(|b| b.contains(p))
    }

    /// True when `p` is inside a collider (a NaN distance from the host's
    /// field counts as inside: never trusted as clear).
    pub(crate) fn inside(&self, p: Vec3) -> bool {
        self.in_shape(p) || !self.field_clear(&[p])
    }

    /// Asks the host's field (if any) once whether every point after the
    /// root of the guide `local` (root frame `frame`, at most
    /// [`MAX_POINTS`] points) is outside when turned by each of `trials`
    /// (at most [`MAX_TRIALS`]); `known[i]` gets the answer for `trials[i]`,
    /// `None` without a field. The points are those a trial of
    /// [`push_out`] makes, bit for bit.
    fn field_trials(
        &self,
        frame: &Frame,
        local: &[Vec3],
        trials: &[Vec2],
        known: &mut [Option<bool>],
    ) {
        let Some(field) = self.all.field else {
            return;
        };
        let n = local.len().min(MAX_POINTS);
        let trials = &trials[..trials.len().min(MAX_TRIALS)];
        let per = n.saturating_sub(1);
        let mut xyz = [[0.0f32; 3]; MAX_TRIALS * MAX_POINTS];
        for (t, w) in trials.iter().enumerate() {
            let turn = Turn::new((*w).into());
            for j in 1..n {
                xyz[t * per + j - 1] = frame.to_world(turned(turn, local[j])).to_array();
            }
        }
        let total = trials.len() * per;
        let mut d = [0.0f32; MAX_TRIALS * MAX_POINTS];
        field.distances(&xyz[..total], &mut d[..total]);
        for (t, k) in known.iter_mut().enumerate().take(trials.len()) {
            *k = Some(d[t * per..(t + 1) * per].iter().all(|&x| x >= 0.0));
        }
    }

    /// True when the host's field (if any) puts every point of `points`
    /// (at most [`MAX_POINTS`]) outside.
    fn field_clear(&self, points: &[Vec3]) -> bool {
        let Some(field) = self.all.field else {
            return true;
        };
        let mut d = [0.0f32; MAX_POINTS];
        let mut xyz = [[0.0f32; 3]; MAX_POINTS];
        let n = points.len().min(MAX_POINTS);
        for (o, p) in xyz.iter_mut().zip(&points[..n]) {
            *o = p.to_array();
        }
        let d = &mut d[..n];
        field.distances(&xyz[..n], d);
        d.iter().all(|&x| x >= 0.0)
    }

    /// The parameter at which the segment `a`-`b`, whose end `b` is
    /// inside, enters the colliders: the largest tried parameter outside,
    /// to 1/4096 of the segment.
    pub(crate) fn entry(&self, a: Vec3, b: Vec3) -> f32 {
        let mut entry = Entry::new();
        for _ in 0..Entry::BISECTIONS {
            entry.narrow(self.inside(entry.next(a, b)));
        }
        entry.out
    }

    /// True when no point of `points` is inside a collider; `hint` as
    /// [`none_inside`] takes it. `field`, when known, is the host field's
    /// answer for these points ([`field_verdicts`]).
    fn clear(&self, points: &[Vec3], hint: &mut usize, field: Option<bool>) -> bool {
        none_inside(points.len(), hint, |j| self.in_shape(points[j]))
            && field.unwrap_or_else(|| self.field_clear(points))
    }
}

/// The bisection of [`Near::entry`], a step at a time, for a caller that
/// asks a host field about many segments' next points at once.
#[derive(Clone, Copy)]
pub(crate) struct Entry {
    /// The largest parameter found outside.
    pub(crate) out: f32,
    /// The smallest found inside.
    inside: f32,
}

impl Entry {
    /// Steps: to 1/4096 of the segment.
    pub(crate) const BISECTIONS: u32 = 12;

    pub(crate) fn new() -> Self {
        Entry {
            out: 0.0,
            inside: 1.0,
        }
    }

    /// The point of `a`-`b` the next step tries.
    pub(crate) fn next(&self, a: Vec3, b: Vec3) -> Vec3 {
        a.lerp(b, 0.5 * (self.out + self.inside))
    }

    /// Takes the verdict on [`next`](Self::next)'s point.
    pub(crate) fn narrow(&mut self, inside: bool) {
        let mid = 0.5 * (self.out + self.inside);
        if inside {
            self.inside = mid;
        } else {
            self.out = mid;
        }
    }
}

/// Marks in `inside` the points of `points` that the host field of
/// `colliders` puts inside (a NaN distance counts as inside: never
/// trusted as clear), asking it once; leaves `inside` as it is without a
/// field.
pub(crate) fn field_inside(
    colliders: &Colliders,
    points: &[[f32; 3]],
    d: &mut [f32],
    inside: &mut [bool],
) {
    let Some(field) = colliders.field else {
        return;
    };
    if points.is_empty() {
        return;
    }
    let d = &mut d[..points.len()];
    field.distances(points, d);
    for (i, &x) in inside.iter_mut().zip(d.iter()) {
        *i |= x.is_nan() || x < 0.0;
    }
}

/// Shape indices a strand is tested against.
#[derive(Clone)]
enum Shapes<'s> {
    Kept(core::slice::Iter<'s, u32>),
    All(core::ops::Range<usize>),
}

impl Iterator for Shapes<'_> {
    type Item = usize;

    fn next(&mut self) -> Option<usize> {
        match self {
            Shapes::Kept(it) => it.next().map(|&i| i as usize),
            Shapes::All(r) => r.next(),
        }
    }
}

/// Most points of one posed guide.
pub const MAX_POINTS: usize = 64;

/// Axes of the tangent plane tried when turning toward the normal is not
/// enough (as settle does).
const AXES: u32 = 8;

/// Most rotations one call of a host field answers for.
const MAX_TRIALS: usize = LIFT_STEPS as usize;

/// Most guides whose points one call of a host field answers for before
/// their push-outs ([`field_verdicts`]): a host pays its per-call cost
/// (a Python callback takes its interpreter's lock) once per batch, and a
/// batch of guides of 16 points asks for some 500 distances.
pub const FIELD_BATCH: usize = 32;

/// Asks the host field of `colliders` once, for up to [`FIELD_BATCH`]
/// guides, what [`push_out`] would first ask it for each: whether every
/// point after the root is outside. `guide(i)` gives guide `i`'s root frame
/// and root-frame points, or `None` to leave it out (a guide not finite,
/// whose points no host should see); `verdicts[i]` gets its answer, `None`
/// where left out or without a field. [`push_out_known`] takes it, with
/// the bits [`push_out`] gives.
pub fn field_verdicts<'g>(
    colliders: &Colliders,
    guide: impl Fn(usize) -> Option<(Frame, &'g [Vec3])>,
    verdicts: &mut [Option<bool>],
) {
    verdicts.fill(None);
    let Some(field) = colliders.field else {
        return;
    };
    let guides = verdicts.len().min(FIELD_BATCH);
    let mut xyz = [[0.0f32; 3]; FIELD_BATCH * MAX_POINTS];
    let mut spans = [(0, 0); FIELD_BATCH];
    let mut total = 0;
    for (i, span) in spans.iter_mut().enumerate().take(guides) {
        let Some((frame, local)) = guide(i) else {
            continue;
        };
        let n = local.len().min(MAX_POINTS);
        let start = total;
        for l in local.iter().take(n).skip(1) {
            xyz[total] = frame.to_world(*l).to_array();
            total += 1;
        }
        *span = (start, total);
        verdicts[i] = Some(true);
    }
    if total == 0 {
        return;
    }
    let mut d = [0.0f32; FIELD_BATCH * MAX_POINTS];
    field.distances(&xyz[..total], &mut d[..total]);
    for (v, span) in verdicts.iter_mut().zip(&spans).take(guides) {
        if let Some(v) = v {
            *v = d[span.0..span.1].iter().all(|&x| x >= 0.0);
        }
    }
}

/// Pushes a posed guide out of the colliders. `local` holds its points in
/// its root frame `frame` (`local[0]` the root), and `reach` bounds its
/// length. Unchanged when every point after the root is outside; else
/// rotated rigidly about the root toward the normal by the smallest clear
/// angle, or about another axis of the tangent plane, or (when nothing
/// frees it) fully toward the normal.
pub fn push_out(colliders: &Colliders, frame: &Frame, local: &mut [Vec3], reach: f32) -> PushOut {
    push_out_known(colliders, frame, local, reach, None)
}

/// [`push_out`] told `field`, the host field's answer for the guide as it
/// is ([`field_verdicts`]), when known: the same bits, the field asked
/// only for the rotations tried.
pub fn push_out_known(
    colliders: &Colliders,
    frame: &Frame,
    local: &mut [Vec3],
    reach: f32,
    field: Option<bool>,
) -> PushOut {
    let n = local.len().min(MAX_POINTS);
    if n < 2 {
        return PushOut::Clear;
    }
    let near = Near::new(colliders, frame.origin, reach);
    if near.is_empty() {
        return PushOut::Clear;
    }
    let mut world = [Vec3::ZERO; MAX_POINTS];
    for (w, l) in world.iter_mut().zip(&local[..n]) {
        *w = frame.to_world(*l);
    }
    let mut hint = 0;
    if near.clear(&world[1..n], &mut hint, field) {
        return PushOut::Clear;
    }
    // a trial turns the point found inside last (the hint) first: most
    // leave it inside, and it answers alone (as `clear` answers then)
    // `known`: the host field's answer for the rotation, when asked before
    let mut clear = |w: Vec2, known: Option<bool>| {
        let turn = Turn::new(w.into());
        let at = |j: usize| frame.to_world(turned(turn, local[j]));
        let first = hint.min(n - 2);
        let tried = at(1 + first);
        if near.in_shape(tried) {
            return false;
        }
        for (j, p) in world[1..n].iter_mut().enumerate() {
            *p = if j == first { tried } else { at(1 + j) };
        }
        let points = &world[1..n];
        none_inside(points.len(), &mut hint, |j| {
            j != first && near.in_shape(points[j])
        }) && known.unwrap_or_else(|| near.field_clear(points))
    };
    // the field is asked once for every lift toward the normal, and once
    // per angle for the axes tried after them
    let (toward, to_normal) = toward_normal(local[n - 1]);
    let lifts: [Vec2; LIFT_STEPS as usize] =
        core::array::from_fn(|k| toward * ((k + 1) as f32 * LIFT_STEP).min(to_normal));
    let mut known = [None; LIFT_STEPS as usize];
    near.field_trials(frame, &local[..n], &lifts, &mut known);
    let lifted = first_clear(to_normal, 1, |a| {
        let w = toward * a;
        let asked = lifts.iter().position(|&l| l == w).and_then(|i| known[i]);
        clear(w, asked)
    })
    .map(|a| toward * a);
    let chosen = lifted.or_else(|| {
        (1..=LIFT_STEPS).find_map(|k| {
            let axes: [Vec2; AXES as usize] = core::array::from_fn(|m| {
                let (s, c) = libm::sincosf(m as f32 * core::f32::consts::TAU / AXES as f32);
                let axis = Vec2::new(toward.x * c - toward.y * s, toward.x * s + toward.y * c);
                axis * (k as f32 * LIFT_STEP).min(FRAC_PI_2)
            });
            let mut known = [None; AXES as usize];
            near.field_trials(frame, &local[..n], &axes, &mut known);
            (0..AXES as usize).find_map(|m| clear(axes[m], known[m]).then_some(axes[m]))
        })
    });
    let turn = Turn::new(chosen.unwrap_or(toward * to_normal).into());
    for l in &mut local[..n] {
        *l = turned(turn, *l);
    }
    if chosen.is_some() {
        PushOut::Freed
    } else {
        PushOut::Stuck
    }
}

/// Root-frame point `l` turned by `turn` about the root (none: unchanged),
/// with the bits [`lift`](crate::collide::lift::lift) gives it.
fn turned(turn: Option<Turn>, l: Vec3) -> Vec3 {
    match turn {
        Some(turn) => {
            let (x, y, z) = turn.apply(l.x, l.y, l.z);
            Vec3::new(x, y, z)
        }
        None => l,
    }
}

/// [`push_out`] for an expanded render strand (paper 3.3: render hairs in
/// user regions): `points` are its world points with their radii, the
/// first its root on `frame`'s origin. Its points are turned about the root
/// as a guide's are; the radii stay. Unchanged (the same bits) when clear.
/// A strand no tried rotation frees (in a crease narrower than it is long)
/// is turned fully toward its normal and then cut where it enters a
/// collider (as trimming cuts): where its first control point inside enters.
pub fn push_out_curve(colliders: &Colliders, frame: &Frame, points: &mut [[f32; 4]]) -> PushOut {
    push_out_curve_known(colliders, frame, points, None)
}

/// A render strand's points (at most [`MAX_POINTS`]) in its root frame, as
/// [`push_out_curve`] turns them, into `local`; returns their count and
/// the strand's length. [`field_verdicts`] on them gives the answer
/// [`push_out_curve_known`] takes.
pub fn curve_local(
    frame: &Frame,
    points: &[[f32; 4]],
    local: &mut [Vec3; MAX_POINTS],
) -> (usize, f32) {
    let n = points.len().min(MAX_POINTS);
    let mut reach = 0.0f32;
    for (j, p) in points[..n].iter().enumerate() {
        local[j] = frame.to_local(Vec3::new(p[0], p[1], p[2]));
        if j > 0 {
            reach += local[j].distance(local[j - 1]);
        }
    }
    (n, reach)
}

/// [`push_out_curve`] told `field`, the host field's answer for the strand
/// as it is, when known: the same bits.
pub fn push_out_curve_known(
    colliders: &Colliders,
    frame: &Frame,
    points: &mut [[f32; 4]],
    field: Option<bool>,
) -> PushOut {
    let mut local = [Vec3::ZERO; MAX_POINTS];
    let (n, reach) = curve_local(frame, points, &mut local);
    let done = push_out_known(colliders, frame, &mut local[..n], reach, field);
    if done == PushOut::Clear {
        return done;
    }
    for (p, l) in points[..n].iter_mut().zip(&local[..n]) {
        let w = frame.to_world(*l);
        (p[0], p[1], p[2]) = (w.x, w.y, w.z);
    }
    if done == PushOut::Stuck {
        let near = Near::new(colliders, frame.origin, reach);
        let at = |j: usize| Vec3::new(points[j][0], points[j][1], points[j][2]);
        if let Some(j) = (1..n).find(|&j| near.inside(at(j))) {
            let t = near.entry(at(j - 1), at(j));
            let length = ((j - 1) as f32 + t) / (n - 1) as f32;
            cut(&mut points[..n], (length * WHOLE as f32) as u16);
        }
    }
    done
}

/// What [`push_out`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PushOut {
    /// Nothing was inside: the guide is unchanged.
    Clear,
    /// The guide was rotated out.
    Freed,
    /// No tried rotation freed it; it was turned fully toward the normal.
    Stuck,
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Whether `Near::new` keeps exactly the capsules the distance keeps:
    /// the count is theirs, and the shapes to test are they, or every
    /// capsule when more than `MAX_NEAR` are near.
    fn keeps_what_the_distance_keeps(capsules: &[Capsule], root: Vec3, reach: f32) -> bool {
        let colliders = Colliders {
            capsules,
            ..Colliders::default()
        };
        let near = Near::new(&colliders, root, reach);
        let want: Vec<usize> = (0..capsules.len())
            .filter(|&i| {
                let c = &capsules[i];
                segment_distance(root, c.a.into(), c.b.into()) < c.radius + reach
            })
            .collect();
        let tested: Vec<usize> = near.shapes(1, &near.capsules, capsules.len()).collect();
        let listed = want.len().min(MAX_NEAR);
        let kept: Vec<usize> = near.capsules[..listed]
            .iter()
            .map(|&i| i as usize)
            .collect();
        let every: Vec<usize> = (0..capsules.len()).collect();
        near.counts[1] == want.len()
            && kept == want[..listed]
            && tested == if want.len() > MAX_NEAR { every } else { want }
    }

    #[test]
    fn more_capsules_near_than_kept_tests_every_capsule() {
        // CI's proptest case: 17 capsules on the root and one just out of
        // reach, 1e6 from the origin; all 18 are tested
        let at = |z: f32| Capsule {
            a: [1e6, 1e6, 1e6 + z],
            b: [1e6, 1e6, 1e6 + z],
            radius: 0.231_246_58,
        };
        let mut capsules = vec![at(0.0); MAX_NEAR + 1];
        capsules.push(at(0.739_996_14));
        assert!(keeps_what_the_distance_keeps(
            &capsules,
            Vec3::splat(1e6),
            0.477_064_3
        ));
        let near_all = Colliders {
            capsules: &capsules,
            ..Colliders::default()
        };
        let near = Near::new(&near_all, Vec3::splat(1e6), 0.477_064_3);
        assert_eq!(near.counts[1], MAX_NEAR + 1);
        assert_eq!(
            near.shapes(1, &near.capsules, capsules.len()).count(),
            capsules.len()
        );
    }

    #[test]
    fn rounding_at_a_far_end_or_underflow_drops_no_capsule() {
        let capsule = |a: [f32; 3], b: [f32; 3], radius| Capsule { a, b, radius };
        // the distance's closest point rounds at the far end's scale
        let long = capsule([-1000.0, 0.0, 0.0], [24.0445, 0.0, 0.0], 0.06);
        assert!(keeps_what_the_distance_keeps(
            &[long],
            Vec3::new(24.10455, 0.0, 0.0),
            0.0
        ));
        let longer = capsule([-1e9, 0.0, 0.0], [40.0, 0.0, 0.0], 5.0);
        assert!(keeps_what_the_distance_keeps(
            &[longer],
            Vec3::new(60.0, 0.0, 0.0),
            0.0
        ));
        // the squared distance underflows to 0
        let tiny = capsule([1e-23, 0.0, 0.0], [1e-23, 0.0, 0.0], 1e-30);
        assert!(keeps_what_the_distance_keeps(&[tiny], Vec3::ZERO, 0.0));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]
        /// The axis box only skips work: the capsules kept near a root are
        /// exactly those the distance keeps, at any offset from the origin
        /// (a creature teleported far away, coordinates up to 1e9), for
        /// short capsules around the root (many boxes leave it out, some
        /// barely) and long ones with a far end, and past the kept list's
        /// length.
        #[test]
        fn near_keeps_exactly_the_capsules_in_reach(
            offset in prop::sample::select(vec![0.0f32, 1.0, 100.0, -3e4, 1e6, -1e9]),
            ends in prop::collection::vec(
                (
                    prop::array::uniform3(-1.0f32..1.0),
                    prop::array::uniform3(-0.2f32..0.2),
                    prop::sample::select(vec![1.0f32, 1.0, 1e3, 1e6, 1e9]),
                ),
                1..40,
            ),
            radius in prop_oneof![Just(0.0f32), 0.0f32..0.3],
            reach in prop_oneof![Just(0.0f32), 0.0f32..0.5],
        ) {
            let shift = |p: Vec3| p + Vec3::splat(offset);
            let capsules: Vec<Capsule> = ends
                .iter()
                .map(|&(a, d, far)| {
                    let a = Vec3::from(a);
                    Capsule { a: shift(a).into(), b: shift(a + Vec3::from(d) * far).into(), radius }
                })
                .collect();
            prop_assert!(keeps_what_the_distance_keeps(&capsules, shift(Vec3::ZERO), reach));
        }
    }

    /// A ball field that counts its calls and the points asked.
    struct CountedBall {
        calls: core::sync::atomic::AtomicUsize,
        points: core::sync::atomic::AtomicUsize,
    }

    impl SignedDistance for CountedBall {
        fn distances(&self, points: &[[f32; 3]], out: &mut [f32]) {
            use core::sync::atomic::Ordering::Relaxed;
            self.calls.fetch_add(1, Relaxed);
            self.points.fetch_add(points.len(), Relaxed);
            for (p, d) in points.iter().zip(out) {
                *d = Vec3::from(*p).distance(Vec3::new(0.0, 0.0, 1.0)) - 0.35;
            }
        }
    }

    #[test]
    fn a_batch_of_field_verdicts_gives_each_push_out_its_bits() {
        use core::sync::atomic::Ordering::Relaxed;
        let ball = CountedBall {
            calls: 0.into(),
            points: 0.into(),
        };
        let colliders = Colliders {
            field: Some(&ball),
            ..Colliders::default()
        };
        // guides standing on a plane under the ball, leaning different
        // ways: some clear, some through it, one left out (not finite)
        let guide = |i: usize| -> (Frame, [Vec3; 16]) {
            let x = -0.6 + 0.04 * i as f32;
            let frame = Frame {
                origin: Vec3::new(x, 0.1 * (i % 3) as f32, 0.0),
                t: Vec3::X,
                b: Vec3::Y,
                n: Vec3::Z,
            };
            let lean = Vec3::new(0.3 * ((i % 5) as f32 - 2.0), 0.1, 1.0).normalize();
            let mut local = [Vec3::ZERO; 16];
            for (k, l) in local.iter_mut().enumerate() {
                *l = lean * (0.1 * k as f32);
            }
            if i == 7 {
                local[3].x = f32::NAN;
            }
            (frame, local)
        };
        let guides: Vec<(Frame, [Vec3; 16])> = (0..FIELD_BATCH).map(guide).collect();
        let mut verdicts = [None; FIELD_BATCH];
        field_verdicts(
            &colliders,
            |i| {
                let (frame, local) = &guides[i];
                local
                    .iter()
                    .all(|p| p.is_finite())
                    .then_some((*frame, &local[..]))
            },
            &mut verdicts,
        );
        assert_eq!(ball.calls.load(Relaxed), 1, "one call for the batch");
        assert_eq!(ball.points.load(Relaxed), (FIELD_BATCH - 1) * 15);
        assert_eq!(verdicts[7], None);
        let (mut freed, mut clear) = (0, 0);
        for (i, (frame, local)) in guides.iter().enumerate().filter(|&(i, _)| i != 7) {
            let (mut asked, mut told) = (*local, *local);
            let a = push_out(&colliders, frame, &mut asked, 1.5);
            let b = push_out_known(&colliders, frame, &mut told, 1.5, verdicts[i]);
            assert_eq!(a, b, "guide {i}");
            assert!(asked == told, "guide {i}: other points");
            freed += (a == PushOut::Freed) as usize;
            clear += (a == PushOut::Clear) as usize;
        }
        assert!(freed >= 3 && clear >= 3, "{freed} freed, {clear} clear");
    }
}
