//! Per-strand groom values from maps.

use crate::buffers::{req, slice, slice_mut};
use crate::status::Failure;
use crate::{PelageMap, PelageMeshDesc, PelageRoot, PelageStatus};
use bytemuck::{Pod, Zeroable};
use pelage_core::interp::groom::{GroomMaps, StrandGroom};
use pelage_core::{Root, ScalarMap};

/// Groom maps sampled at each strand root; start from pelage_groom_maps_defaults().
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageGroomMaps {
    /// Length multiplier (default 1).
    pub length: PelageMap,
    /// Width (diameter) at the root in world units (default 0.002).
    pub root_width: PelageMap,
    /// Width at the tip (default 0.0005).
    pub tip_width: PelageMap,
    /// Curl toward the root tangent, tip offset as a fraction of length (default 0).
    pub bend: PelageMap,
    /// Kink amplitude as a fraction of length (default 0).
    pub kink_amplitude: PelageMap,
    /// Kink waves along the strand (default 3).
    pub kink_frequency: PelageMap,
    /// Pull of the tip toward the clump centre guide, 0..1 (default 0).
    pub clump: PelageMap,
    /// Random variation of the length, 0..1 (default 0): each strand keeps
    /// `1 - v u` of its length, `u` uniform in [0, 1) per strand id.
    pub length_random: PelageMap,
    /// Random variation of the clump pull, 0..1 (default 0), likewise:
    /// soft clump borders.
    pub clump_random: PelageMap,
    /// Seed of the per-strand random values (kink phase, the variations).
    pub seed: u64,
}

/// Groom values of one strand.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PelageStrandGroom {
    /// Length multiplier.
    pub length: f32,
    /// Radius at the root.
    pub root_radius: f32,
    /// Radius at the tip.
    pub tip_radius: f32,
    /// Bend.
    pub bend: f32,
    /// Kink amplitude.
    pub kink_amplitude: f32,
    /// Kink frequency.
    pub kink_frequency: f32,
    /// Kink phase as the unit vector (cos, sin) of the angle.
    pub kink_phase: [f32; 2],
    /// Clump pull.
    pub clump: f32,
    /// Rotation of the strand about its root: a rotation vector in the root
    /// frame's tangent plane (tangent, bitangent; length = angle in radians).
    /// 0 from the maps; pelage_settle sets it where a strand would enter the body.
    pub lift: [f32; 2],
}

same_layout!(
    PelageStrandGroom,
    StrandGroom,
    length,
    root_radius,
    tip_radius,
    bend,
    kink_amplitude,
    kink_frequency,
    kink_phase,
    clump,
    lift
);

/// A default map as a C constant map. Every default is a constant (the
/// core's `GroomMaps::default` documents it); anything else would read as
/// 0, never panic outside a boundary.
fn constant(m: &ScalarMap) -> PelageMap {
    match m {
        ScalarMap::Constant(c) => PelageMap::constant(*c),
        _ => PelageMap::constant(0.0),
    }
}

/// Default groom maps (constants; see the field docs), seed 0.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_groom_maps_defaults() -> PelageGroomMaps {
    let d = GroomMaps::default();
    PelageGroomMaps {
        length: constant(&d.length),
        root_width: constant(&d.root_width),
        tip_width: constant(&d.tip_width),
        bend: constant(&d.bend),
        kink_amplitude: constant(&d.kink_amplitude),
        kink_frequency: constant(&d.kink_frequency),
        clump: constant(&d.clump),
        length_random: constant(&d.length_random),
        clump_random: constant(&d.clump_random),
        seed: 0,
    }
}

/// Samples the groom maps at `root_count` strand roots (once per groom) into
/// `grooms` (capacity `grooms_capacity`). Nothing is written on failure.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (a map's kind, size or
/// stride; a texture map without mesh uvs), NON_FINITE, OUT_OF_RANGE (a
/// root's face), CAPACITY_EXCEEDED (`grooms_capacity`), MISALIGNED, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_groom_evaluate(
    mesh: *const PelageMeshDesc,
    maps: *const PelageGroomMaps,
    roots: *const PelageRoot,
    root_count: usize,
    grooms: *mut PelageStrandGroom,
    grooms_capacity: usize,
) -> PelageStatus {
    ffi_boundary! {
        let desc = req(mesh, "mesh")?;
        let mesh = desc.view()?;
        let m = req(maps, "maps")?;
        let nv = desc.vertex_count;
        let core = GroomMaps {
            length: m.length.view(nv, "length map")?,
            root_width: m.root_width.view(nv, "root width map")?,
            tip_width: m.tip_width.view(nv, "tip width map")?,
            bend: m.bend.view(nv, "bend map")?,
            kink_amplitude: m.kink_amplitude.view(nv, "kink amplitude map")?,
            kink_frequency: m.kink_frequency.view(nv, "kink frequency map")?,
            clump: m.clump.view(nv, "clump map")?,
            length_random: m.length_random.view(nv, "length random map")?,
            clump_random: m.clump_random.view(nv, "clump random map")?,
        };
        let roots: &[Root] = bytemuck::cast_slice(slice(roots, root_count, "roots")?);
        if grooms_capacity < root_count {
            return Err(Failure::new(
                PelageStatus::CapacityExceeded,
                format!("grooms: {root_count} needed, {grooms_capacity} available"),
            ));
        }
        let out = slice_mut(grooms, root_count, "grooms")?;
        // the core checks every input before it writes the first record
        core.evaluate(&mesh, roots, m.seed, bytemuck::cast_slice_mut(out))?;
        Ok(())
    }
}
