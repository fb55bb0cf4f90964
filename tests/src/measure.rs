//! Shared helpers for the end-to-end tests and benchmarks: running the core
//! with `Vec`-backed memory, a uniform random baseline, and spacing statistics.

use crate::creature::CreatureMesh;
use glam::Vec3;
use pelage_core::rng::{self, Purpose};
use pelage_core::stamp::{self, StampParams, StampReport};
use pelage_core::surface::grid::HashGrid;
use pelage_core::{Arena, Mesh, Root, Strided};

/// Borrows a creature mesh as a core mesh (with UVs and normals).
pub fn mesh_view(m: &CreatureMesh) -> Mesh<'_> {
    let mut mesh = Mesh::new(
        Strided::from_slice(&m.positions),
        Strided::from_slice(&m.triangles),
    );
    mesh.uvs = (!m.uvs.is_empty()).then(|| Strided::from_slice(&m.uvs));
    mesh.normals = (!m.normals.is_empty()).then(|| Strided::from_slice(&m.normals));
    mesh
}

/// Stamps with heap memory sized by the core's own queries.
pub fn stamp_vec(mesh: Mesh, params: &StampParams) -> (Vec<Root>, StampReport) {
    let mut arena = vec![0u8; stamp::required_bytes(&mesh, params).expect("valid input")];
    let mut roots = vec![Root::default(); stamp::max_roots(&mesh, params).expect("valid input")];
    let (n, report) =
        stamp::stamp(mesh, params, &mut Arena::new(&mut arena), &mut roots).expect("stamp");
    roots.truncate(n);
    (roots, report)
}

/// Stamps `n` roots with `seed` and default parameters.
pub fn stamp_roots(mesh: Mesh, n: u32, seed: u64) -> Vec<Root> {
    let params = StampParams {
        target_count: n,
        seed,
        ..StampParams::default()
    };
    stamp_vec(mesh, &params).0
}

/// `n` roots placed uniformly at random by area (the baseline stamping is
/// compared against), skipping degenerate faces.
pub fn uniform_roots(mesh: &Mesh, n: usize, seed: u64) -> Vec<Root> {
    let faces = mesh.triangle_count();
    let mut cdf = Vec::with_capacity(faces);
    let mut total = 0.0f64;
    for f in 0..faces {
        if !mesh.is_degenerate(f) {
            total += mesh.area(f) as f64;
        }
        cdf.push(total);
    }
    (0..n)
        .map(|i| {
            let h = |c| rng::hash(seed, i as u64, Purpose::Uniform, c);
            let x = (h(0) >> 11) as f64 / (1u64 << 53) as f64 * total;
            let face = cdf.partition_point(|&c| c <= x).min(faces - 1);
            let (mut u, mut v) = (rng::to_unit(h(1)), rng::to_unit(h(2)));
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            Root {
                face: face as u32,
                u,
                v,
                id: i as u32,
                rank: i as u32,
            }
        })
        .collect()
}

/// Positions and face normals of roots.
pub fn root_points(mesh: &Mesh, roots: &[Root]) -> Vec<(Vec3, Vec3)> {
    roots
        .iter()
        .map(|r| {
            (
                mesh.point(r.face as usize, r.u, r.v),
                mesh.face_normal(r.face as usize),
            )
        })
        .collect()
}

/// Nearest-neighbour distance statistics, ignoring pairs on opposite sides
/// of a thin part (opposed normals).
#[derive(Clone, Copy, Debug)]
pub struct Spacing {
    /// Smallest nearest-neighbour distance.
    pub min: f32,
    /// Mean nearest-neighbour distance.
    pub mean: f32,
}

/// Nearest-neighbour distances of `points`, searched within `max_dist`
/// (a point with no neighbour that close counts as `max_dist`).
pub fn spacing(points: &[(Vec3, Vec3)], max_dist: f32) -> Spacing {
    let n = points.len();
    let mut heads = vec![0u32; HashGrid::buckets_for(n)];
    let mut next = vec![0u32; n];
    let cell = max_dist / 2.0;
    let mut grid = HashGrid::new(&mut heads, &mut next, cell);
    for (i, p) in points.iter().enumerate() {
        grid.insert(i as u32, p.0);
    }
    let (mut min, mut sum) = (f32::INFINITY, 0.0f64);
    for (i, p) in points.iter().enumerate() {
        let mut best = max_dist * max_dist;
        grid.any_within(p.0, max_dist, |j| {
            let q = &points[j as usize];
            if j as usize != i && p.1.dot(q.1) > 0.0 {
                best = best.min(p.0.distance_squared(q.0));
            }
            false
        });
        let d = best.sqrt();
        min = min.min(d);
        sum += d as f64;
    }
    Spacing {
        min,
        mean: (sum / n.max(1) as f64) as f32,
    }
}

/// The spacing of `n` points on a perfect hexagonal lattice over `area`:
/// sqrt(2A / (sqrt(3) N)).
pub fn r_hex(area: f64, n: usize) -> f32 {
    (2.0 * area / (3f64.sqrt() * n as f64)).sqrt() as f32
}

/// Guide curves of `cvs` points on `roots`: leaving along the normal and
/// combed toward -y, bending gently, `length` long. Stored point after point.
pub fn combed_guides(mesh: &Mesh, roots: &[Root], cvs: usize, length: f32) -> Vec<[f32; 3]> {
    let mut pts = Vec::with_capacity(roots.len() * cvs);
    for r in roots {
        let (f, u, v) = (r.face as usize, r.u, r.v);
        let p = mesh.point(f, u, v);
        let n = mesh.normal(f, u, v);
        let down = Vec3::NEG_Y - n * n.dot(Vec3::NEG_Y);
        let comb = down.normalize_or_zero();
        let seg = length / (cvs - 1) as f32;
        let mut q = p;
        pts.push(q.into());
        for j in 1..cvs {
            let t = j as f32 / (cvs - 1) as f32;
            let dir = (n * (1.0 - 0.6 * t) + comb * (0.6 * t)).normalize();
            q += dir * seg;
            pts.push(q.into());
        }
    }
    pts
}

/// Binds `hairs` to the guides of `cvs` points on `mesh` at rest (default
/// parameters).
pub fn bind_vec(
    mesh: &Mesh,
    guide_roots: &[Root],
    guide_points: &[[f32; 3]],
    cvs: usize,
    hairs: &[Root],
) -> Vec<pelage_core::interp::bind::StrandBinding> {
    use pelage_core::interp::bind::{self, BindParams, StrandBinding};
    let guides = pelage_core::guides::Guides {
        roots: guide_roots,
        points: Strided::from_slice(guide_points),
        layout: pelage_core::guides::CvLayout::Fixed(cvs),
    };
    let mut arena = vec![0u8; bind::required_bytes(mesh, guide_roots.len()).unwrap()];
    let mut bindings = vec![StrandBinding::default(); hairs.len()];
    let params = BindParams::default();
    bind::bind(
        mesh,
        &guides,
        hairs,
        &params,
        &mut Arena::new(&mut arena),
        &mut bindings,
    )
    .unwrap();
    bindings
}

/// A groom made through the C API on a mesh: guides and strands stamped
/// (seeds 1 and 2), the guides combed, the strands bound and their groom
/// maps evaluated.
pub struct Groomed {
    /// Guide roots.
    pub guide_roots: Vec<Root>,
    /// Their points, `cvs` per guide.
    pub guide_points: Vec<[f32; 3]>,
    /// Strand roots.
    pub strands: Vec<Root>,
    /// One binding per strand.
    pub bindings: Vec<pelage::PelageStrandBinding>,
    /// One groom record per strand.
    pub grooms: Vec<pelage::PelageStrandGroom>,
    /// What binding reported.
    pub info: pelage::PelageBindInfo,
}

/// Grooms `m` with `guides` combed guides of `cvs` points and `length`,
/// and `strands` strands bound on `threads` threads with `maps`.
pub fn groomed(
    m: &CreatureMesh,
    (guides, cvs, length): (u32, usize, f32),
    strands: u32,
    maps: &pelage::PelageGroomMaps,
    threads: u32,
) -> Groomed {
    use pelage::*;
    let mesh = mesh_view(m);
    let guide_roots = stamp_roots(mesh, guides, 1);
    let guide_points = combed_guides(&mesh, &guide_roots, cvs, length);
    let strands = stamp_roots(mesh, strands, 2);
    let d = mesh_desc(m);
    let g = guides_desc(&guide_roots, &guide_points);
    let c_strands = bytemuck::cast_slice::<Root, PelageRoot>(&strands);
    let params = PelageBindParams {
        run: on_threads(threads),
        ..pelage_bind_params_defaults()
    };
    let mut bytes = 0usize;
    assert_eq!(
        pelage_bind_size(&d, guide_roots.len(), &mut bytes),
        PelageStatus::Ok
    );
    let mut arena = vec![0u8; bytes];
    let mut bindings = vec![PelageStrandBinding::default(); strands.len()];
    let mut info = PelageBindInfo::default();
    let s = pelage_bind(
        &PelageRestPose {
            mesh: &d,
            guides: &g,
        },
        c_strands.as_ptr(),
        strands.len(),
        &params,
        PelageArena {
            memory: arena.as_mut_ptr().cast(),
            bytes,
        },
        bindings.as_mut_ptr(),
        bindings.len(),
        &mut info,
    );
    assert_eq!(s, PelageStatus::Ok);
    let mut grooms = vec![PelageStrandGroom::default(); strands.len()];
    let s = pelage_groom_evaluate(
        &d,
        maps,
        c_strands.as_ptr(),
        strands.len(),
        grooms.as_mut_ptr(),
        grooms.len(),
    );
    assert_eq!(s, PelageStatus::Ok);
    Groomed {
        guide_roots,
        guide_points,
        strands,
        bindings,
        grooms,
        info,
    }
}

impl Groomed {
    /// The guides as a C API description (borrows them).
    pub fn guides(&self) -> pelage::PelageGuidesDesc {
        guides_desc(&self.guide_roots, &self.guide_points)
    }

    /// Settles the grooms out of `m`'s body with `params` (`pelage_settle`).
    pub fn settle(
        &mut self,
        m: &CreatureMesh,
        params: &pelage::PelageExpandParams,
    ) -> pelage::PelageSettleInfo {
        use pelage::*;
        let d = mesh_desc(m);
        let mut bytes = 0usize;
        assert_eq!(
            pelage_settle_size(&d, self.guide_roots.len(), params, &mut bytes),
            PelageStatus::Ok
        );
        let mut arena = vec![0u8; bytes];
        let mut info = PelageSettleInfo::default();
        let s = pelage_settle(
            &PelageRestPose {
                mesh: &d,
                guides: &self.guides(),
            },
            bytemuck::cast_slice::<Root, PelageRoot>(&self.strands).as_ptr(),
            self.bindings.as_ptr(),
            self.grooms.as_mut_ptr(),
            self.strands.len(),
            params,
            PelageArena {
                memory: arena.as_mut_ptr().cast(),
                bytes,
            },
            &mut info,
        );
        assert_eq!(s, PelageStatus::Ok);
        info
    }
}

/// The creature as a C API mesh description (borrows `m`): `uvs` and
/// `normals` are NULL when `m` has none (empty Vecs).
pub fn mesh_desc(m: &CreatureMesh) -> pelage::PelageMeshDesc {
    let or_null = |empty: bool, p: *const std::ffi::c_void| {
        if empty {
            std::ptr::null()
        } else {
            p
        }
    };
    pelage::PelageMeshDesc {
        positions: m.positions.as_ptr().cast(),
        position_stride: 12,
        vertex_count: m.positions.len(),
        indices: m.triangles.as_ptr().cast(),
        index_stride: 12,
        triangle_count: m.triangles.len(),
        uvs: or_null(m.uvs.is_empty(), m.uvs.as_ptr().cast()),
        uv_stride: 8,
        normals: or_null(m.normals.is_empty(), m.normals.as_ptr().cast()),
        normal_stride: 12,
    }
}

/// Guides with a fixed point count as a C API description (borrows both slices).
pub fn guides_desc(roots: &[Root], points: &[[f32; 3]]) -> pelage::PelageGuidesDesc {
    pelage::PelageGuidesDesc {
        roots: bytemuck::cast_slice::<Root, pelage::PelageRoot>(roots).as_ptr(),
        guide_count: roots.len(),
        points: points.as_ptr().cast(),
        point_stride: 12,
        point_count: points.len(),
        points_per_guide: (points.len() / roots.len().max(1)) as u32,
        offsets: std::ptr::null(),
    }
}

/// A frame handle, freed on drop.
pub struct Frame(pub pelage::PelageFrame);

impl Drop for Frame {
    fn drop(&mut self) {
        pelage::pelage_frame_free(self.0);
    }
}

/// A run of `threads` threads with no progress callback.
pub fn on_threads(threads: u32) -> pelage::PelageRun {
    pelage::PelageRun {
        thread_count: threads,
        ..pelage::pelage_run_defaults()
    }
}

/// A frame of `mesh` posed with `guides` for `points` points per strand,
/// or the first failing status.
pub fn frame(
    mesh: &pelage::PelageMeshDesc,
    guides: &pelage::PelageGuidesDesc,
    points: u32,
    threads: u32,
) -> Result<Frame, pelage::PelageStatus> {
    let mut handle = std::ptr::null_mut();
    let s = pelage::pelage_frame_new(mesh, guides.guide_count, points, &mut handle);
    if s != pelage::PelageStatus::Ok {
        return Err(s);
    }
    let frame = Frame(handle);
    match pelage::pelage_frame_set_guides(frame.0, guides, on_threads(threads)) {
        pelage::PelageStatus::Ok => Ok(frame),
        s => Err(s),
    }
}

/// Strand records as the C API's descriptor (borrows the slices).
pub fn strands_desc(
    roots: &[Root],
    bindings: &[pelage::PelageStrandBinding],
    grooms: &[pelage::PelageStrandGroom],
) -> pelage::PelageStrands {
    pelage::PelageStrands {
        roots: bytemuck::cast_slice::<Root, pelage::PelageRoot>(roots).as_ptr(),
        bindings: bindings.as_ptr(),
        grooms: grooms.as_ptr(),
        count: roots.len(),
    }
}

/// A groom handle (`pelage_groom_new`) of the strands `roots` with their
/// bindings and groom records; free it with `pelage_groom_free`.
pub fn groom_handle(
    roots: &[Root],
    bindings: &[pelage::PelageStrandBinding],
    grooms: &[pelage::PelageStrandGroom],
) -> pelage::PelageGroom {
    let strands = strands_desc(roots, bindings, grooms);
    let mut handle = std::ptr::null_mut();
    assert_eq!(
        pelage::pelage_groom_new(&strands, &mut handle),
        pelage::PelageStatus::Ok
    );
    handle
}

/// Packed float4 curves (stride 16) into `out`, optionally with counts.
pub fn curves_desc(out: &mut [[f32; 4]], counts: Option<&mut [u32]>) -> pelage::PelageCurves {
    pelage::PelageCurves {
        points: out.as_mut_ptr().cast(),
        point_stride: 16,
        point_capacity: out.len(),
        curve_counts: counts.map_or(std::ptr::null_mut(), |c| c.as_mut_ptr()),
        curve_ids: std::ptr::null_mut(),
    }
}

/// The borrowed inputs of a frame and a `pelage_expand` call, so tests
/// state only what differs.
pub struct ExpandCall<'a> {
    /// The (deformed) mesh.
    pub mesh: &'a pelage::PelageMeshDesc,
    /// The (posed) guides.
    pub guides: &'a pelage::PelageGuidesDesc,
    /// Strand roots.
    pub strands: &'a [Root],
    /// One binding per strand.
    pub bindings: &'a [pelage::PelageStrandBinding],
    /// One groom record per strand.
    pub grooms: &'a [pelage::PelageStrandGroom],
    /// Expansion parameters.
    pub params: &'a pelage::PelageExpandParams,
}

impl ExpandCall<'_> {
    /// Makes the frame and expands every strand into `out` (capacity
    /// `out.len()` points, stride 16), optionally filling per-curve point
    /// counts; the first failing status otherwise.
    pub fn run(&self, out: &mut [[f32; 4]], counts: Option<&mut [u32]>) -> pelage::PelageStatus {
        let p = self.params;
        let frame = match frame(
            self.mesh,
            self.guides,
            p.points_per_strand,
            p.run.thread_count,
        ) {
            Ok(f) => f,
            Err(s) => return s,
        };
        self.run_on(&frame, out, counts)
    }

    /// Expands every strand on `frame` (see [`ExpandCall::run`]).
    pub fn run_on(
        &self,
        frame: &Frame,
        out: &mut [[f32; 4]],
        counts: Option<&mut [u32]>,
    ) -> pelage::PelageStatus {
        let strands = strands_desc(self.strands, self.bindings, self.grooms);
        let curves = curves_desc(out, counts);
        pelage::pelage_expand(frame.0, &strands, self.params, &curves)
    }
}

/// A simulation handle with its memory, freed on drop.
pub struct SimHandle {
    pub sim: pelage::PelageSim,
    _memory: Vec<u8>,
}

impl SimHandle {
    /// The simulation of the rest pose `mesh` and `guides` with `params`.
    pub fn new(
        mesh: &pelage::PelageMeshDesc,
        guides: &pelage::PelageGuidesDesc,
        params: &pelage::PelageSimParams,
    ) -> SimHandle {
        use pelage::PelageStatus;
        let mut bytes = 0;
        let s = pelage::pelage_sim_size(mesh, guides.guide_count, params, &mut bytes);
        assert_eq!(s, PelageStatus::Ok, "pelage_sim_size");
        let mut memory = vec![0u8; bytes];
        let mut sim = std::ptr::null_mut();
        let s = pelage::pelage_sim_new(
            &pelage::PelageRestPose { mesh, guides },
            params,
            pelage::PelageArena {
                memory: memory.as_mut_ptr().cast(),
                bytes,
            },
            &mut sim,
        );
        assert_eq!(s, PelageStatus::Ok, "pelage_sim_new");
        SimHandle {
            sim,
            _memory: memory,
        }
    }

    /// The posed guides of the last step: `guides` of `points` points.
    pub fn read(&self, guides: usize, points: usize) -> Vec<[f32; 3]> {
        let mut out = vec![[0.0f32; 3]; guides * points];
        let s = pelage::pelage_sim_read(self.sim, out.as_mut_ptr().cast(), 12, out.len());
        assert_eq!(s, pelage::PelageStatus::Ok, "pelage_sim_read");
        out
    }
}

impl Drop for SimHandle {
    fn drop(&mut self) {
        pelage::pelage_sim_free(self.sim);
    }
}
