//! The groom handle: a groom's render strands, checked once and kept for
//! expanding every frame.

use crate::buffers::{req, req_mut, slice};
use crate::expand::{run, Curves};
use crate::status::Failure;
use crate::{
    PelageExpandParams, PelageGuidesDesc, PelageMeshDesc, PelageRoot, PelageStatus,
    PelageStrandBinding, PelageStrandGroom,
};
use pelage_core::interp::bind::StrandBinding;
use pelage_core::interp::expand::{StrandBounds, Strands};
use pelage_core::interp::groom::StrandGroom;
use pelage_core::Root;
use std::ffi::c_void;

/// The opaque object a `PelageGroom` points to.
// not repr(C): cbindgen declares it in C without a definition
pub struct PelageGroomTy {
    _private: [u8; 0],
}

/// A groom: render strands (roots, bindings, groom values) copied and
/// checked once by `pelage_groom_new`, so that `pelage_groom_expand` checks
/// per frame only the mesh, the posed guides and the outputs. Created by
/// `pelage_groom_new`, released by `pelage_groom_free`; immutable between.
pub type PelageGroom = *mut PelageGroomTy;

/// What a [`PelageGroom`] points to.
struct Groom {
    roots: Vec<Root>,
    bindings: Vec<StrandBinding>,
    grooms: Vec<StrandGroom>,
    bounds: StrandBounds,
}

impl Groom {
    fn strands(&self) -> Strands<'_> {
        Strands {
            roots: &self.roots,
            bindings: &self.bindings,
            grooms: &self.grooms,
        }
    }
}

/// The groom behind a handle, or NULL_PARAMETER. A non-NULL handle must
/// come from `pelage_groom_new` and not be freed yet (the header's
/// contract), so it points to a live `Groom`.
fn groom_ref<'a>(groom: PelageGroom) -> Result<&'a Groom, Failure> {
    req(groom.cast::<Groom>().cast_const(), "groom")
}

/// Creates a groom from `strand_count` render strands: parallel arrays of
/// roots, bindings (from `pelage_bind`) and groom values (from
/// `pelage_groom_evaluate` or the host). The records are checked (faces,
/// barycentrics, guide indices, weights, groom values) and copied: the host
/// may free or change its arrays afterwards. On success `*out_groom` is the
/// new groom; on failure it is left untouched.
///
/// Thread safety: may be called from any thread at any time.
#[no_mangle]
pub extern "C" fn pelage_groom_new(
    strands: *const PelageRoot,
    bindings: *const PelageStrandBinding,
    grooms: *const PelageStrandGroom,
    strand_count: usize,
    out_groom: *mut PelageGroom,
) -> PelageStatus {
    ffi_boundary! {
        let out = req_mut(out_groom, "out_groom")?;
        let roots: &[Root] = bytemuck::cast_slice(slice(strands, strand_count, "strands")?);
        let bindings: &[StrandBinding] = bytemuck::cast_slice(slice(bindings, strand_count, "bindings")?);
        let grooms: &[StrandGroom] = bytemuck::cast_slice(slice(grooms, strand_count, "grooms")?);
        let bounds = StrandBounds::new(&Strands { roots, bindings, grooms })?;
        let groom = Box::new(Groom {
            roots: roots.to_vec(),
            bindings: bindings.to_vec(),
            grooms: grooms.to_vec(),
            bounds,
        });
        *out = Box::into_raw(groom).cast::<PelageGroomTy>();
        Ok(())
    }
}

/// Releases a groom. NULL is accepted and does nothing.
///
/// Thread safety: no other call may use `groom` during or after this one.
#[no_mangle]
pub extern "C" fn pelage_groom_free(groom: PelageGroom) {
    if groom.is_null() {
        return;
    }
    // a panic while dropping plain vectors cannot happen; the boundary is
    // kept so that no exported body can unwind into the host
    let _ = std::panic::catch_unwind(|| {
        // SAFETY: `groom` came from pelage_groom_new and is freed once, as
        // the header requires.
        drop(unsafe { Box::from_raw(groom.cast::<Groom>()) });
    });
}

/// Writes the number of strands in `groom` to `*strand_count`.
///
/// Thread safety: may be called from any thread while `groom` is alive.
#[no_mangle]
pub extern "C" fn pelage_groom_strand_count(
    groom: PelageGroom,
    strand_count: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let groom = groom_ref(groom)?;
        *req_mut(strand_count, "strand_count")? = groom.roots.len();
        Ok(())
    }
}

/// `pelage_expand` for the strands `first .. first + count` of `groom`:
/// the same outputs and bits, without reading every strand record again
/// to check it (the records were checked by `pelage_groom_new`; only that
/// they fit this frame's mesh and guides is checked). The range is how a
/// render procedural expands patch by patch.
///
/// Thread safety: concurrent calls on the same groom are safe with distinct
/// arenas and outputs.
#[no_mangle]
pub extern "C" fn pelage_groom_expand(
    groom: PelageGroom,
    mesh: *const PelageMeshDesc,
    guides: *const PelageGuidesDesc,
    first: usize,
    count: usize,
    params: *const PelageExpandParams,
    arena: *mut c_void,
    arena_bytes: usize,
    points: *mut c_void,
    point_stride: usize,
    point_capacity: usize,
    curve_counts: *mut u32,
    curve_ids: *mut u32,
) -> PelageStatus {
    ffi_boundary! {
        let groom = groom_ref(groom)?;
        let total = groom.roots.len();
        let range = first..first.checked_add(count).filter(|&end| end <= total).ok_or_else(|| {
            Failure::new(PelageStatus::OutOfRange, format!("strands {first} + {count} exceed the groom's {total}"))
        })?;
        let out = Curves { points, point_stride, point_capacity, curve_counts, curve_ids };
        run(mesh, guides, groom.strands().range(range), Some(&groom.bounds), params, arena, arena_bytes, out)
    }
}
