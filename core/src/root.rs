//! The hair root record: where a strand grows, and who it is.

use bytemuck::{Pod, Zeroable};

/// One hair root on the mesh: a point in barycentric form plus its identity.
///
/// The position is `(1 - u - v) p0 + u p1 + v p2` on triangle `face`, so it
/// follows the mesh through any deformation that keeps the topology.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Root {
    /// Triangle index.
    pub face: u32,
    /// Barycentric weight of the triangle's second vertex.
    pub u: f32,
    /// Barycentric weight of the triangle's third vertex.
    pub v: f32,
    /// Permanent strand identity: seeds every per-strand random number.
    pub id: u32,
    /// LOD rank, a permutation of `0..n`: the roots with `rank < k` are an
    /// evenly spread subset of `k` roots, for any `k`.
    pub rank: u32,
}

const _: () = assert!(core::mem::size_of::<Root>() == 20);

/// Slack on the barycentric range a root may have (stamped roots sit exactly
/// inside; hosts may round).
pub(crate) const BARYCENTRIC_SLACK: f32 = 1e-4;

/// Checks that every root is on an existing face, inside it.
pub fn check_roots(
    mesh: &crate::Mesh,
    roots: &[Root],
    what: &'static str,
) -> Result<(), crate::Error> {
    let faces = mesh.triangle_count();
    for (i, r) in roots.iter().enumerate() {
        check_root(faces, r, what).map_err(|e| e.shifted(i))?;
    }
    Ok(())
}

/// Checks that `r` is on one of `faces` faces, inside it (element index 0).
pub(crate) fn check_root(faces: usize, r: &Root, what: &'static str) -> Result<(), crate::Error> {
    if r.face as usize >= faces {
        return Err(crate::Error::OutOfRange {
            what,
            index: 0,
            value: r.face as usize,
            bound: faces,
        });
    }
    if !(r.u.is_finite() && r.v.is_finite()) {
        return Err(crate::Error::NonFinite { what, index: 0 });
    }
    let e = BARYCENTRIC_SLACK;
    if r.u < -e || r.v < -e || r.u + r.v > 1.0 + e {
        return Err(crate::Error::InvalidArgument(
            "a root's barycentric coordinates lie outside its triangle",
        ));
    }
    Ok(())
}
