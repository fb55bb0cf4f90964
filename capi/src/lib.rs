//! pelage C API: a thin layer that validates host buffers, calls
//! `pelage-core`, and maps errors to [`PelageStatus`] codes.
//!
//! Every exported function runs inside `ffi_boundary!`, so a panic becomes
//! `PELAGE_STATUS_PANIC` instead of unwinding into the host.
#![deny(missing_docs)]

#[macro_use]
mod status;
mod bind;
mod body;
mod buffers;
mod colliders;
mod expand;
mod frame;
mod groom;
mod groom_file;
mod groom_handle;
mod guide_cache;
mod guides;
mod handles;
mod map;
mod mesh;
mod patch;
mod region;
mod roots;
mod settle;
mod sim;
mod stamp;
mod threads;
pub use threads::{pelage_run_defaults, PelageProgressFn, PelageRun};
mod trim;

pub use bind::{
    pelage_bind, pelage_bind_params_defaults, pelage_bind_size, PelageBindInfo, PelageBindParams,
    PelageStrandBinding, PELAGE_MAX_NEIGHBOURS, PELAGE_WEIGHT_SUM_TOLERANCE,
};
pub use buffers::PelageArena;
pub use colliders::{PelageCapsule, PelageColliders, PelageDistanceFn, PelagePlane, PelageSphere};
pub use expand::{
    pelage_curves_segment_indices, pelage_expand, pelage_expand_params_defaults,
    pelage_expand_size, PelageCurves, PelageEndPoints, PelageExpandParams, PelageStrands,
};
pub use frame::{
    pelage_frame_free, pelage_frame_inside, pelage_frame_new, pelage_frame_origin,
    pelage_frame_set_colliders, pelage_frame_set_guides, pelage_frame_set_origin,
    pelage_frame_signed_distance, PelageFrame, PelageFrameTy,
};
pub use groom::{
    pelage_groom_evaluate, pelage_groom_maps_defaults, PelageGroomMaps, PelageStrandGroom,
};
pub use groom_file::{
    pelage_groom_file_info, pelage_groom_file_read, pelage_groom_file_write,
    PelageGroomFileBuffers, PelageGroomFileDesc, PelageGroomFileInfo, PelagePatch,
};
pub use groom_handle::{
    pelage_groom_expand, pelage_groom_expand_edited, pelage_groom_free, pelage_groom_lod_counts,
    pelage_groom_new, pelage_groom_strand_count, PelageGroom, PelageGroomTy, PelageStrandEdits,
};
pub use guide_cache::{
    pelage_guide_cache_info, pelage_guide_cache_read, pelage_guide_cache_size,
    pelage_guide_cache_write, PelageGuideCacheInfo, PelageGuideSet,
};
pub use guides::{PelageGuidesDesc, PelageRestPose};
pub use map::{pelage_map_mask, PelageMap, PelageMapKind};
pub use mesh::PelageMeshDesc;
pub use patch::{pelage_patch_boxes, pelage_patch_plan};
pub use region::{PelageRegionKind, PelageRegionMap};
pub use roots::{pelage_roots_evaluate, PelageRoot};
pub use settle::{pelage_settle, pelage_settle_size, PelageSettleInfo};
pub use sim::{
    pelage_frame_set_sim_guides, pelage_sim_free, pelage_sim_new, pelage_sim_origin,
    pelage_sim_params_defaults, pelage_sim_read, pelage_sim_reset, pelage_sim_restore,
    pelage_sim_save, pelage_sim_size, pelage_sim_state_size, pelage_sim_step,
    pelage_step_params_defaults, PelageSim, PelageSimParams, PelageSimTy, PelageStepInfo,
    PelageStepParams,
};
pub use stamp::{
    pelage_stamp, pelage_stamp_params_defaults, pelage_stamp_size, PelageStampInfo,
    PelageStampParams,
};
pub use status::{pelage_last_error, pelage_status_message, PelageStatus};
pub use trim::{
    pelage_trim_find, pelage_trim_lengths_read, pelage_trim_lengths_size,
    pelage_trim_lengths_write, pelage_trim_records_info, pelage_trim_records_read,
    pelage_trim_records_size, pelage_trim_records_write, pelage_trim_shortest,
    pelage_trim_shortest_hairs, PelageTrimRecord, PelageTrimRecordsInfo, PELAGE_TRIM_WHOLE,
};

/// Major version of the library this header belongs to.
pub const PELAGE_VERSION_MAJOR: u32 = 0;
/// Minor version.
pub const PELAGE_VERSION_MINOR: u32 = 12;
/// Patch version.
pub const PELAGE_VERSION_PATCH: u32 = 0;

/// The library's version as `major * 10000 + minor * 100 + patch`; compare it
/// with the header's PELAGE_VERSION_* macros to detect a mismatched binary.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_version() -> u32 {
    PELAGE_VERSION_MAJOR * 10000 + PELAGE_VERSION_MINOR * 100 + PELAGE_VERSION_PATCH
}
