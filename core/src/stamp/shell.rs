//! Separate shells and buried skin. Production meshes are often several
//! pieces that touch or pass through each other (eyeballs in their
//! sockets, a horn or an ear modelled apart), and have holes (eye sockets,
//! a mouth). The stamp keeps its spacing across shells and grows no hair
//! where the skin is buried:
//! - **Spacing across shells.** Points of a face that comes within its disk
//!   radius of a face of another shell take part in the edge pass and every
//!   LOD level (as points near a cut edge do), so the spacing holds between
//!   the shells as it holds across cuts. A face is looked at within
//!   [`REACH_MARGIN`] of its radius, so a coarser LOD level's points of two
//!   shells farther apart than that are not compared.
//! - **Buried skin.** A point is dropped when the spot just outside the
//!   skin there (a thousandth of the local disk radius along the face
//!   normal) is inside the body with its holes closed by caps (fans from
//!   the mean of each hole's rim), by the
//!   winding number (see [`Body::capped_winding`]): skin inside another
//!   shell (the part of the head a horn passes through, the horn's base
//!   inside the head, an eyeball behind the rim of its socket) grows no
//!   hair. A mesh of one closed shell has no buried skin and skips the
//!   test. The winding number changes only across a surface, so the faces
//!   no other shell and no cap comes near are decided a patch at a time
//!   (faces joined by shared corners), at the centroid of the patch's first
//!   face; skin buried by its own shell passing through itself is not
//!   looked for, as on a mesh of one closed shell.

use super::place::BURY_LIFT;
use crate::arena::{Arena, ArenaLayout};
use crate::surface::body::{Body, BodyPlan, Rim};
use crate::surface::grid::floor_i32;
use crate::{Error, Mesh};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// `p` lifted `lift` along `n`, and never by less than 16 float32 steps of
/// its largest coordinate: far from the origin a thousandth of the disk
/// radius rounds away (a metre head at 1e3, roots 2 mm apart, against a
/// float spacing of 6e-5) and leaves the point on the skin, where the
/// winding number's answer is noise and whole patches were called buried.
fn lifted(p: Vec3, n: Vec3, lift: f32) -> Vec3 {
    let room = p.abs().max_element() * 16.0 * f32::EPSILON;
    p + n * lift.max(room)
}

/// Per-face bit: the face comes within its reach of another shell.
const NEAR_OTHER: u8 = 1;
/// Per-face bit: the face comes within its reach of a hole's cap.
const NEAR_CAP: u8 = 2;
/// Per-face bit, on a face neither near bit is set on: its skin is buried
/// as a whole.
const BURIED: u8 = 4;
/// Per-face bit, on a face a near bit is set on: the edge of buried skin
/// crosses it (some corners' skin is buried, some not).
const BURIAL_EDGE: u8 = 8;

/// What the stamp knows of a mesh's shells.
pub(super) struct Shells<'a> {
    /// Per face, [`NEAR_OTHER`] and [`NEAR_CAP`], or [`BURIED`] on a face
    /// neither is set on.
    flags: &'a [u8],
    /// The body, when some skin may be buried (several shells, or holes).
    body: Option<Body<'a>>,
}

/// How far past its disk radius a face looks for other shells: the radius
/// correction moves the radius by a few percent.
pub(super) const REACH_MARGIN: f32 = 1.5;

/// A cell of the grid [`mark_near_other_shells`] hashes the faces into,
/// and the shell of every face whose box meets it ([`MIXED`] for several).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Cell {
    key: [i32; 3],
    shell: u32,
}

/// [`Cell::shell`] of a free slot.
const EMPTY: u32 = u32::MAX;
/// [`Cell::shell`] of a cell faces of several shells meet.
const MIXED: u32 = u32::MAX - 1;
/// Slots a cell may take from its hash on.
const PROBES: usize = 16;

/// Slots of the cell table for a mesh of `faces` faces: a power of two.
/// The cells are about a face's size and reach, so most faces share their
/// cells with others and the table stays under half full.
fn cell_slots(faces: usize) -> usize {
    (2 * faces).next_power_of_two()
}

impl<'a> Shells<'a> {
    /// Adds the bytes [`Shells::new`] may take for `mesh` (validated).
    pub(super) fn layout(layout: &mut ArenaLayout, mesh: &Mesh) {
        let faces = mesh.triangle_count();
        layout
            .add::<u32>(mesh.positions.len())
            .add::<u8>(faces)
            .add::<u8>(mesh.positions.len())
            .add::<Cell>(cell_slots(faces))
            .add::<u8>(Rim::required_bytes(mesh))
            .add::<u8>(Body::required_bytes(mesh).unwrap_or(0));
    }

    /// Labels the shells of `mesh` and, when there are several or the mesh
    /// is open, flags the faces near another shell (each face reaching
    /// `reach(f)`, 0 for a face without roots) and builds the body.
    pub(super) fn new(
        mesh: &Mesh,
        reach: impl Fn(usize) -> f32,
        arena: &mut Arena<'a>,
    ) -> Result<Self, Error> {
        let faces = mesh.triangle_count();
        if mesh.positions.len() >= 1 << 31 {
            return Err(Error::InvalidArgument("over 2^31 vertices"));
        }
        let rim = Rim::new(mesh, arena)?;
        let parent = arena.alloc::<u32>(mesh.positions.len())?;
        join_corners(mesh, &rim, parent, |_| true);
        for v in 0..parent.len() as u32 {
            let r = root(parent, v);
            parent[v as usize] = r;
        }
        // each shell counted once, at its first face, by a mark on its root
        const COUNTED: u32 = 1 << 31;
        let mut shells = 0;
        for [a, ..] in mesh.triangles.iter() {
            let r = (parent[a as usize] & !COUNTED) as usize;
            shells += (parent[r] & COUNTED == 0) as usize;
            parent[r] |= COUNTED;
        }
        let shell_of = |f: usize| parent[mesh.triangles.get(f)[0] as usize] & !COUNTED;
        let near = arena.alloc::<u8>(faces)?;
        near.fill(0);
        if shells > 1 {
            mark_near_other_shells(mesh, &shell_of, &reach, near, arena)?;
        }
        mark_near_caps(mesh, &rim, &reach, near);
        if shells == 1 && rim.is_closed() {
            return Ok(Shells {
                flags: near,
                body: None,
            });
        }
        let body = Body::build(&BodyPlan::of(mesh, &rim)?, mesh, &rim, arena)?;
        // patches of the faces with roots that nothing comes near
        let free = |near: &[u8], f: usize| near[f] == 0 && reach(f) > 0.0;
        join_corners(mesh, &rim, parent, |f| free(near, f));
        const UNDECIDED: u8 = u8::MAX;
        let decided = arena.alloc::<u8>(mesh.positions.len())?;
        decided.fill(UNDECIDED);
        for (f, [a, ..]) in mesh.triangles.iter().enumerate() {
            if free(near, f) {
                let patch = root(parent, a) as usize;
                if decided[patch] == UNDECIDED {
                    // the lift at the first radius: on a face nothing comes
                    // near, the lift changes the answer only at a crease
                    let lift = BURY_LIFT * reach(f) / REACH_MARGIN;
                    let [a, b, c] = mesh.corners(f);
                    let p = lifted((a + b + c) / 3.0, mesh.face_normal(f), lift);
                    decided[patch] = (body.capped_winding(p) >= 1) as u8 * BURIED;
                }
                near[f] = decided[patch];
            }
        }
        // the faces near something whose corners' skin is partly buried,
        // each corner tested once (lifted along the normal of its first such
        // face: only where the fill looks depends on it, and each dart is
        // tested on its own)
        decided.fill(UNDECIDED);
        for (f, corners) in mesh.triangles.iter().enumerate() {
            if near[f] & (NEAR_OTHER | NEAR_CAP) == 0 || reach(f) <= 0.0 {
                continue;
            }
            let lift = BURY_LIFT * reach(f) / REACH_MARGIN;
            let normal = mesh.face_normal(f);
            let mut seen = 0u8;
            for v in corners {
                let state = &mut decided[v as usize];
                if *state == UNDECIDED {
                    let p = lifted(Vec3::from(mesh.positions.get(v as usize)), normal, lift);
                    *state = (body.capped_winding(p) >= 1) as u8;
                }
                seen |= 1 << *state;
            }
            if seen == 3 {
                near[f] |= BURIAL_EDGE;
            }
        }
        Ok(Shells {
            flags: near,
            body: Some(body),
        })
    }

    /// Whether the edge of buried skin crosses some face (see
    /// [`burial_edge`](Self::burial_edge)).
    #[inline]
    pub(super) fn has_burial_edges(&self) -> bool {
        self.flags.iter().any(|&f| f & BURIAL_EDGE != 0)
    }

    /// Whether the edge of buried skin crosses face `f` (a face another
    /// shell or a cap comes near, whose corners' skin is partly buried):
    /// the placement dropped its points on one side, and the fill throws
    /// darts all over it to refill the skin beside them.
    #[inline]
    pub(super) fn burial_edge(&self, f: usize) -> bool {
        self.flags[f] & BURIAL_EDGE != 0
    }

    /// Whether face `f` comes within its reach of another shell.
    #[inline]
    pub(super) fn near_other(&self, f: usize) -> bool {
        self.flags[f] & NEAR_OTHER != 0
    }

    /// Whether the skin at `p` on a face of unit normal `n` is buried:
    /// `lift` along the normal is inside the body with its holes capped.
    #[inline]
    pub(super) fn buried(&self, p: Vec3, n: Vec3, lift: f32) -> bool {
        self.body
            .as_ref()
            .is_some_and(|b| b.capped_winding(lifted(p, n, lift)) >= 1)
    }

    /// Whether all of face `f` (with roots) is buried (`Some`), or `None`
    /// when its points must be tested one by one: on a face no other shell
    /// and no cap comes near, the skin a hair off it is all buried or all
    /// free (up to the lift at a crease), as is its whole patch.
    #[inline]
    pub(super) fn face_buried(&self, f: usize) -> Option<bool> {
        if self.body.is_none() {
            return Some(false);
        }
        match self.flags[f] {
            0 => Some(false),
            BURIED => Some(true),
            _ => None,
        }
    }
}

/// Union-find over the welded vertices of `mesh` (a UV seam joins its two
/// sides) into `parent`, each face `joins` accepts joining its corners; the
/// larger root joins the smaller, so the labels do not depend on the order
/// of the unions.
fn join_corners(mesh: &Mesh, rim: &Rim, parent: &mut [u32], joins: impl Fn(usize) -> bool) {
    for (i, p) in parent.iter_mut().enumerate() {
        *p = rim.welded(i as u32);
    }
    for (f, [a, b, c]) in mesh.triangles.iter().enumerate() {
        if joins(f) {
            for other in [b, c] {
                let (ra, rb) = (root(parent, a), root(parent, other));
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
        }
    }
}

/// The root of vertex `v` in the union-find `parent`, halving the path.
fn root(parent: &mut [u32], mut v: u32) -> u32 {
    while parent[v as usize] != v {
        let up = parent[parent[v as usize] as usize];
        parent[v as usize] = up;
        v = up;
    }
    v
}

/// Flags the faces whose box, widened by their reach, meets the ball around
/// a hole's cap (the mean of the loop's corners, out to its farthest).
fn mark_near_caps(mesh: &Mesh, rim: &Rim, reach: &dyn Fn(usize) -> f32, near: &mut [u8]) {
    for k in 0..rim.loop_count() {
        let (mean, radius) = rim.ball(k, mesh);
        for (f, flag) in near.iter_mut().enumerate() {
            let [a, b, c] = mesh.corners(f);
            let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
            let gap = mean.clamp(lo, hi).distance(mean);
            if gap <= radius * 1.001 + reach(f) {
                *flag |= NEAR_CAP;
            }
        }
    }
}

/// Flags the faces whose box, widened by their reach, shares a cell of a
/// grid with the box of a face of another shell (bald ones included). A
/// face within reach of another always shares one. Only the asking face's
/// box is widened: two points of different shells clash within the
/// smaller of their faces' radii, so within the reach of both faces, and
/// both are flagged. The cells live in a
/// hash table keyed by their coordinates, each with the shell of its faces
/// or [`MIXED`]; a cell that finds no slot within [`PROBES`] of its hash
/// counts as holding another shell, which only flags more faces than
/// needed (their points then take part in the edge pass for nothing).
fn mark_near_other_shells(
    mesh: &Mesh,
    shell_of: &dyn Fn(usize) -> u32,
    reach: &dyn Fn(usize) -> f32,
    near: &mut [u8],
    arena: &mut Arena,
) -> Result<(), Error> {
    let faces = mesh.triangle_count();
    let table = arena.alloc::<Cell>(cell_slots(faces))?;
    table.fill(Cell {
        key: [0; 3],
        shell: EMPTY,
    });
    // cells about the size of a face and its reach
    let mut extent = 0.0f64;
    let mut counted = 0usize;
    for f in 0..faces {
        let r = reach(f);
        if r > 0.0 {
            let [a, b, c] = mesh.corners(f);
            extent += ((a.max(b).max(c) - a.min(b).min(c)).max_element() + r) as f64;
            counted += 1;
        }
    }
    if counted == 0 {
        return Ok(());
    }
    // cells near the mean face, coarse enough that the largest face
    // covers at most 17 cells a side
    let largest = (0..faces)
        .filter(|&f| reach(f) > 0.0)
        .map(|f| {
            let [a, b, c] = mesh.corners(f);
            (a.max(b).max(c) - a.min(b).min(c)).max_element() + reach(f)
        })
        .fold(0.0f32, f32::max);
    let inv_cell = (counted as f64 / extent).min(16.0 / largest as f64);
    let boxed = |f: usize, pad: f32| {
        let [a, b, c] = mesh.corners(f);
        let pad = Vec3::splat(pad);
        let cell = |p: Vec3| (p * inv_cell as f32).to_array().map(floor_i32);
        (cell(a.min(b).min(c) - pad), cell(a.max(b).max(c) + pad))
    };
    let mask = table.len() - 1;
    let slots = |key: [i32; 3]| {
        let [x, y, z] = key.map(|k| k as u32);
        let mut h =
            x.wrapping_mul(0x9E37_79B1) ^ y.wrapping_mul(0x85EB_CA77) ^ z.wrapping_mul(0xC2B2_AE3D);
        h = (h ^ (h >> 15)).wrapping_mul(0x2C1B_3C6D);
        let h = (h ^ (h >> 13)) as usize;
        (0..PROBES).map(move |k| h.wrapping_add(k) & mask)
    };
    let cells = |f: usize, pad: f32, visit: &mut dyn FnMut([i32; 3])| {
        let (lo, hi) = boxed(f, pad);
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    visit([x, y, z]);
                }
            }
        }
    };
    // bald faces too: a hairy face that a bald shell passes through must
    // be flagged (its skin is partly buried)
    for f in (0..faces).filter(|&f| !mesh.is_degenerate(f)) {
        let s = shell_of(f);
        cells(f, 0.0, &mut |key| {
            for i in slots(key) {
                let cell = &mut table[i];
                if cell.shell == EMPTY {
                    *cell = Cell { key, shell: s };
                    return;
                }
                if cell.key == key {
                    cell.shell = if cell.shell == s { s } else { MIXED };
                    return;
                }
            }
        });
    }
    // whether the cell holds a face of a shell other than `s`: a free slot
    // ends the probe (the cell holds no face); a cell whose probe finds
    // neither may have found no slot, and counts as holding one
    let other = |key: [i32; 3], s: u32| {
        for i in slots(key) {
            if table[i].shell == EMPTY {
                return false;
            }
            if table[i].key == key {
                return table[i].shell != s;
            }
        }
        true
    };
    for f in (0..faces).filter(|&f| reach(f) > 0.0) {
        let mut any = false;
        let s = shell_of(f);
        cells(f, reach(f), &mut |key| any |= other(key, s));
        near[f] = any as u8 * NEAR_OTHER;
    }
    Ok(())
}
