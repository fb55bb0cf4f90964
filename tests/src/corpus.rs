//! A corpus of production-like meshes (issue 48, ask 1), built
//! procedurally: heads open at the eyes and the mouth, with eyeballs,
//! teeth and ears as separate shells that cut through the head, a 90 degree
//! brow, slivers, zero-area triangles, a non-manifold edge and ears thinner
//! than the hair spacing; with and without UVs, in centimetres and in
//! metres, at the origin, rotated, and 1e3 and 1e4 from the origin.
//!
//! Almost every figure the project measured came from the test creature
//! (`crate::creature`: one closed, UV-mapped shell at the origin); the
//! meshes artists hand over look like these instead. [`corpus`] is the
//! whole list (for benches: a row per mesh, and the worst one);
//! [`representative`] is a coarse subset cheap enough for every stage's
//! tests. Each entry also gives a closed single-shell mesh of the same size,
//! triangle count, UVs and placement ([`CorpusMesh::closed_reference`]),
//! for "the same mesh closed" ratios.
//!
//! # The corpus head
//!
//! Grown from `crate::head` (see `corpus/head.rs` for the construction).
//! At scale 1 it is about one unit across; y is up, +z the front. In face
//! order, its parts ([`CorpusMesh::parts`]) are:
//!
//! - `head`: a shell meshed on meridians, fine at the front and coarse at
//!   the back (slivers fan around the top pole and where meridians with
//!   different row counts are zipped), open at the neck, at two almond eye
//!   sockets and at a smiling mouth. Each hole's rim is pushed inward by a
//!   depth that varies along it (deepest at the inner eye corners and the
//!   mouth corners), so no rim is planar. A **box brow** over both eyes
//!   ends in a 90 degree step (a convex crease on top, a concave one at its
//!   foot, as at the eye corners the issue measured); the step tapers to
//!   zero height at both ends, where it leaves four **zero-area triangles**
//!   (two vertices in the same place) and slivers beside them. A stray
//!   **fin** triangle stands on an edge at the back of the head: that edge
//!   has three faces.
//! - `eye` x2: closed spheres in the sockets that stick out of the holes
//!   and cut through the head shell around the rims.
//! - `tooth` x8: closed ellipsoids hanging from the upper lip into the
//!   mouth; the lip's skin passes through each.
//! - `ear` x2: closed flattened ellipsoids on the sides of the crown, their
//!   base inside the head, at most 0.008 (x scale) thick: thinner than the
//!   hair spacing of the counts tested (r_hex is 0.020 at 10K roots and
//!   0.009 at 50K on the unit head).
//!
//! So the head shell has 4 boundary loops (two eyes, mouth, neck) and one
//! open boundary chain (the fin's two free edges), and the mesh has 13
//! shells (head, 2 eyes, 8 teeth, 2 ears).
//!
//! # No UVs
//!
//! A mesh without UVs has an empty `uvs` Vec; [`mesh_desc`] then passes a
//! NULL `uvs` pointer, as the C API documents for absent UVs, and
//! [`mesh_view`] no UVs (the same for normals). Without UVs a mesh keeps its triangles, so the same
//! root (face, u, v) is the same point with and without UVs; its vertices
//! stay split along the former UV seams, as an exporter that drops UVs
//! leaves them.

mod head;
pub mod report;
pub mod topology;

use std::ops::Range;

use glam::{DQuat, DVec3};

use crate::creature::CreatureMesh;
pub use crate::measure::{mesh_desc, mesh_view};
pub use head::{Detail, COARSE, EAR_HALF_THICK, FULL, TEETH};

/// Scale of a centimetre scene: the head is about 25 units across.
pub const CM: f64 = 25.0;
/// Scale of a metre scene: the head is about 0.25 units across.
pub const M: f64 = 0.25;

/// The direction the far placements move the mesh along (unit length; all
/// three coordinates are large, so each one loses precision).
pub const FAR_DIRECTION: DVec3 = DVec3::new(0.8, 0.36, -0.48);

/// The rigid rotation of the rotated placements: 0.7 radians about
/// (1, 2, 3) / sqrt(14).
pub fn rotation() -> DQuat {
    DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7)
}

/// The mesh moved rigidly: each position `p` becomes `rotation * p +
/// offset`, computed in f64 from the f32 input and rounded once to f32
/// (as a host moves a character whose asset is in f32); normals are
/// rotated, triangles and UVs kept.
pub fn placed(mesh: &CreatureMesh, offset: DVec3, rotation: DQuat) -> CreatureMesh {
    let move_point = |p: &[f32; 3]| {
        let p = DVec3::from(p.map(f64::from));
        (rotation * p + offset).as_vec3().to_array()
    };
    let turn = |n: &[f32; 3]| {
        let n = DVec3::from(n.map(f64::from));
        (rotation * n).normalize_or_zero().as_vec3().to_array()
    };
    CreatureMesh {
        positions: mesh.positions.iter().map(move_point).collect(),
        triangles: mesh.triangles.clone(),
        uvs: mesh.uvs.clone(),
        normals: mesh.normals.iter().map(turn).collect(),
    }
}

/// The mesh turned by `turn` about the centre of its bounds and moved by
/// `shift`, rigidly ([`placed`]): a frame of a host's animation.
pub fn turned_about_centre(mesh: &CreatureMesh, turn: DQuat, shift: DVec3) -> CreatureMesh {
    let (mut lo, mut hi) = (DVec3::MAX, DVec3::MIN);
    for p in &mesh.positions {
        let p = DVec3::from(p.map(f64::from));
        (lo, hi) = (lo.min(p), hi.max(p));
    }
    let centre = (lo + hi) / 2.0;
    placed(mesh, centre - turn * centre + shift, turn)
}

/// What a corpus mesh is built from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// The corpus head at a resolution.
    Head(Detail),
    /// `crate::head::head()`, the head the project tested before the
    /// corpus (open at the eyes and the neck, no mouth, no crease).
    Legacy,
    /// The closed single-shell reference of about this many triangles.
    Closed(usize),
}

/// How a corpus mesh is made: its shape, scale, attributes and placement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Recipe {
    /// The shape.
    pub shape: Shape,
    /// Uniform scale applied to the unit-sized shape (before rounding to f32).
    pub scale: f64,
    /// Whether the mesh has UVs.
    pub uvs: bool,
    /// Whether the mesh has vertex normals.
    pub normals: bool,
    /// Translation of the placement (see [`placed`]).
    pub offset: DVec3,
    /// Rotation of the placement.
    pub rotation: DQuat,
}

/// A named range of faces of a corpus mesh.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Part {
    /// What the part is: `head`, `eye`, `tooth`, `ear`, `horn`, `closed`.
    pub name: &'static str,
    /// Its faces, contiguous.
    pub faces: Range<usize>,
}

/// What a corpus mesh promises about itself at the origin (the tests check
/// each). Far from the origin, rounding to f32 may put two vertices of a
/// fine part in one place, which changes what welding by position sees
/// (more zero-area faces, edges with more faces): the promises hold for
/// the mesh's index topology, which a placement keeps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Expect {
    /// Simple closed boundary loops (open holes).
    pub boundary_loops: usize,
    /// Open boundary chains (the free edges of the fin).
    pub open_chains: usize,
    /// Connected shells.
    pub shells: usize,
    /// Edges with three faces.
    pub non_manifold_edges: usize,
    /// Zero-area triangles, at least (a placement far from the origin may
    /// collapse some slivers too).
    pub zero_area_faces: usize,
    /// Whether some edge joins faces at about 90 degrees (normals' dot
    /// product at most 0.1).
    pub crease: bool,
    /// A part whose two sides are at most this far apart (mesh units).
    pub thin: Option<(&'static str, f64)>,
}

/// One mesh of the corpus.
#[derive(Clone, Debug)]
pub struct CorpusMesh {
    /// A short unique name (`head_cm_no_uvs_1e4`, ...).
    pub name: String,
    /// What it exercises, in a sentence.
    pub about: &'static str,
    /// How it was made ([`Recipe::build`] makes it again).
    pub recipe: Recipe,
    /// The mesh; `uvs` (`normals`) empty when it has none.
    pub mesh: CreatureMesh,
    /// Its parts, in face order, covering every face.
    pub parts: Vec<Part>,
    /// What it promises.
    pub expect: Expect,
}

impl Recipe {
    /// The recipe at `scale` with UVs and normals, at the origin.
    pub fn new(shape: Shape, scale: f64) -> Self {
        Recipe {
            shape,
            scale,
            uvs: true,
            normals: true,
            offset: DVec3::ZERO,
            rotation: DQuat::IDENTITY,
        }
    }

    /// Without UVs.
    pub fn no_uvs(self) -> Self {
        Recipe { uvs: false, ..self }
    }

    /// Without normals.
    pub fn no_normals(self) -> Self {
        Recipe {
            normals: false,
            ..self
        }
    }

    /// Rotated by [`rotation`] and moved `distance` along
    /// [`FAR_DIRECTION`].
    pub fn rotated_at(self, distance: f64) -> Self {
        Recipe {
            offset: FAR_DIRECTION * distance,
            rotation: rotation(),
            ..self
        }
    }

    /// The same recipe unmoved: the mesh this one is [`placed`] from.
    pub fn at_origin(self) -> Self {
        Recipe {
            offset: DVec3::ZERO,
            rotation: DQuat::IDENTITY,
            ..self
        }
    }

    /// Whether the placement moves the mesh.
    pub fn is_placed(&self) -> bool {
        self.offset != DVec3::ZERO || self.rotation != DQuat::IDENTITY
    }

    /// A point of the placed mesh back in the frame of the unplaced one
    /// (in f64): `rotation^-1 (p - offset)`.
    pub fn local(&self, p: DVec3) -> DVec3 {
        self.rotation.inverse() * (p - self.offset)
    }

    /// Builds the mesh.
    pub fn build(&self) -> (CreatureMesh, Vec<Part>, Expect) {
        let thin_ear = Some(("ear", 2.0 * EAR_HALF_THICK * self.scale));
        let (mut mesh, parts, expect) = match self.shape {
            Shape::Head(detail) => {
                let b = head::build(&detail, self.scale);
                let expect = Expect {
                    boundary_loops: 4,
                    open_chains: 1,
                    shells: 5 + TEETH,
                    non_manifold_edges: 1,
                    zero_area_faces: 4,
                    crease: true,
                    thin: thin_ear,
                };
                (b.mesh, b.parts, expect)
            }
            Shape::Closed(triangles) => {
                let b = head::closed(triangles, self.scale);
                (b.mesh, b.parts, Expect::closed())
            }
            Shape::Legacy => {
                let (mut m, p) = crate::head::head_with_parts();
                if self.scale != 1.0 {
                    for q in &mut m.positions {
                        *q = q.map(|x| (x as f64 * self.scale) as f32);
                    }
                }
                let mut parts = vec![("head", p.head)];
                parts.extend(p.eyes.map(|e| ("eye", e)));
                parts.push(("horn", p.horn));
                parts.extend(p.ears.map(|e| ("ear", e)));
                let expect = Expect {
                    boundary_loops: crate::head::HEAD_BOUNDARY_LOOPS,
                    shells: 6,
                    ..Expect::closed()
                };
                (m, parts, expect)
            }
        };
        if !self.uvs {
            mesh.uvs = Vec::new();
        }
        if !self.normals {
            mesh.normals = Vec::new();
        }
        if self.is_placed() {
            mesh = placed(&mesh, self.offset, self.rotation);
        }
        let parts = parts
            .into_iter()
            .map(|(name, faces)| Part { name, faces })
            .collect();
        (mesh, parts, expect)
    }
}

impl Expect {
    /// A closed single shell with no pathology.
    pub fn closed() -> Self {
        Expect {
            boundary_loops: 0,
            open_chains: 0,
            shells: 1,
            non_manifold_edges: 0,
            zero_area_faces: 0,
            crease: false,
            thin: None,
        }
    }
}

impl CorpusMesh {
    /// Builds the mesh of `recipe`.
    pub fn new(name: impl Into<String>, about: &'static str, recipe: Recipe) -> Self {
        let (mesh, parts, expect) = recipe.build();
        CorpusMesh {
            name: name.into(),
            about,
            recipe,
            mesh,
            parts,
            expect,
        }
    }

    /// Whether the mesh has UVs.
    pub fn has_uvs(&self) -> bool {
        !self.mesh.uvs.is_empty()
    }

    /// The mesh as a C API description (see [`mesh_desc`]).
    pub fn desc(&self) -> pelage::PelageMeshDesc {
        mesh_desc(&self.mesh)
    }

    /// The mesh as a core mesh (see [`mesh_view`]).
    pub fn view(&self) -> pelage_core::Mesh<'_> {
        mesh_view(&self.mesh)
    }

    /// Roots the stamp writes through the C API for `target` roots and
    /// `seed` (default parameters otherwise), its report and the time of
    /// the `pelage_stamp` call.
    pub fn stamp(
        &self,
        target: u32,
        seed: u64,
    ) -> (
        Vec<pelage_core::Root>,
        pelage::PelageStampInfo,
        std::time::Duration,
    ) {
        use pelage::{PelageRoot, PelageStatus};
        let desc = self.desc();
        let params = pelage::PelageStampParams {
            target_count: target,
            seed,
            ..pelage::pelage_stamp_params_defaults()
        };
        let (mut bytes, mut max) = (0usize, 0usize);
        let s = pelage::pelage_stamp_size(&desc, &params, &mut bytes, &mut max);
        assert_eq!(s, PelageStatus::Ok, "{}: pelage_stamp_size", self.name);
        let mut arena = vec![0u8; bytes];
        let mut roots = vec![PelageRoot::default(); max];
        let (mut count, mut info) = (0usize, pelage::PelageStampInfo::default());
        let t0 = std::time::Instant::now();
        let s = pelage::pelage_stamp(
            &desc,
            &params,
            pelage::PelageArena {
                memory: arena.as_mut_ptr().cast(),
                bytes,
            },
            roots.as_mut_ptr(),
            roots.len(),
            &mut count,
            &mut info,
        );
        let time = t0.elapsed();
        assert_eq!(s, PelageStatus::Ok, "{}: pelage_stamp", self.name);
        roots.truncate(count);
        let roots = bytemuck::cast_slice::<PelageRoot, pelage_core::Root>(&roots).to_vec();
        (roots, info, time)
    }

    /// The shell of every face (connected components, numbered in face
    /// order: the head shell is 0).
    pub fn shells(&self) -> Vec<u32> {
        topology::shells(&self.mesh).0
    }

    /// The faces of every part called `name`.
    pub fn part_faces(&self, name: &str) -> Vec<Range<usize>> {
        self.parts
            .iter()
            .filter(|p| p.name == name)
            .map(|p| p.faces.clone())
            .collect()
    }

    /// The same mesh built at the origin, unrotated (itself when it is not
    /// placed).
    pub fn at_origin(&self) -> CorpusMesh {
        CorpusMesh::new(
            format!("{}@origin", self.name),
            self.about,
            self.recipe.at_origin(),
        )
    }

    /// A closed single shell as large as this mesh, with about as many
    /// triangles, the same UVs and normals (present or not) and the same
    /// placement: the "same mesh closed" of ratios in benches.
    pub fn closed_reference(&self) -> CorpusMesh {
        let recipe = Recipe {
            shape: Shape::Closed(self.mesh.triangle_count()),
            ..self.recipe
        };
        CorpusMesh::new(
            format!("{}_closed", self.name),
            "a closed single shell as large as the mesh, as many triangles",
            recipe,
        )
    }
}

/// The whole corpus (14 meshes of 44,908 triangles, and the legacy head's
/// 85,440):
///
/// | name | exercises |
/// |---|---|
/// | `head_cm` | the corpus head in a centimetre scene (25 units across): open rims, 13 shells, creases, zero-area faces, a non-manifold edge, thin ears |
/// | `head_cm_rot` | the same, rotated at the origin: answers that must not depend on orientation |
/// | `head_cm_1e3` | rotated and 1e3 from the origin (10 m in cm): float32 world points |
/// | `head_cm_1e4` | rotated and 1e4 from the origin (100 m in cm): the worst placement |
/// | `head_cm_no_uvs` | without UVs: root frames from the faces alone |
/// | `head_cm_no_uvs_rot`, `_1e3`, `_1e4` | without UVs and moved: where the issue saw guides turn |
/// | `head_m` | a metre scene (0.25 units across): absolute epsilons |
/// | `head_m_no_uvs` | metre scale without UVs |
/// | `head_m_1e3`, `head_m_1e4` | metre scale far away (1 km, 10 km): float32 spacing near the hair length |
/// | `head_bare_cm` | neither UVs nor normals: face normals only |
/// | `legacy_head` | `crate::head`, the head tested before the corpus (85,440 triangles, unit scale) |
///
/// Every entry's [`CorpusMesh::closed_reference`] gives its closed twin.
pub fn corpus() -> Vec<CorpusMesh> {
    let head = |scale| Recipe::new(Shape::Head(FULL), scale);
    let mut out = Vec::new();
    for (name, recipe) in [("head_cm", head(CM)), ("head_cm_no_uvs", head(CM).no_uvs())] {
        let about = if recipe.uvs {
            "the corpus head in centimetres"
        } else {
            "the corpus head in centimetres, without UVs"
        };
        out.push(CorpusMesh::new(name, about, recipe));
        out.push(CorpusMesh::new(
            format!("{name}_rot"),
            about,
            recipe.rotated_at(0.0),
        ));
        for (far, d) in [("1e3", 1e3), ("1e4", 1e4)] {
            out.push(CorpusMesh::new(
                format!("{name}_{far}"),
                about,
                recipe.rotated_at(d),
            ));
        }
    }
    let about = "the corpus head in metres";
    out.push(CorpusMesh::new("head_m", about, head(M)));
    out.push(CorpusMesh::new(
        "head_m_no_uvs",
        "the corpus head in metres, without UVs",
        head(M).no_uvs(),
    ));
    out.push(CorpusMesh::new(
        "head_m_1e3",
        about,
        head(M).rotated_at(1e3),
    ));
    out.push(CorpusMesh::new(
        "head_m_1e4",
        about,
        head(M).rotated_at(1e4),
    ));
    out.push(CorpusMesh::new(
        "head_bare_cm",
        "the corpus head in centimetres with neither UVs nor normals",
        head(CM).no_uvs().no_normals(),
    ));
    out.push(CorpusMesh::new(
        "legacy_head",
        "the head tested before the corpus (crate::head)",
        Recipe::new(Shape::Legacy, 1.0),
    ));
    out
}

/// The representative subset: the corpus head at [`COARSE`] resolution
/// (11,964 triangles), cheap enough to run every stage on in a test:
///
/// | name | exercises |
/// |---|---|
/// | `coarse_cm` | centimetres at the origin with UVs: open non-planar rims (eyes, mouth, neck), eyeballs, teeth and ears as separate intersecting shells, the 90 degree brow, zero-area faces and slivers, the non-manifold fin, ears thinner than the hair spacing |
/// | `coarse_cm_no_uvs` | the same faces without UVs (root frames from the faces alone) |
/// | `coarse_m_1e3` | metre scale, rotated and 1e3 from the origin, with UVs |
/// | `coarse_cm_no_uvs_1e4` | no UVs, rotated and 1e4 from the origin: the worst case of the issue |
///
/// [`CorpusMesh::at_origin`] gives each moved mesh unmoved, for
/// comparisons ("the same answers anywhere in the scene").
pub fn representative() -> Vec<CorpusMesh> {
    let head = |scale| Recipe::new(Shape::Head(COARSE), scale);
    vec![
        CorpusMesh::new(
            "coarse_cm",
            "every pathology, centimetres, at the origin, with UVs",
            head(CM),
        ),
        CorpusMesh::new(
            "coarse_cm_no_uvs",
            "every pathology, centimetres, at the origin, without UVs",
            head(CM).no_uvs(),
        ),
        CorpusMesh::new(
            "coarse_m_1e3",
            "every pathology, metres, rotated and 1e3 from the origin",
            head(M).rotated_at(1e3),
        ),
        CorpusMesh::new(
            "coarse_cm_no_uvs_1e4",
            "every pathology, centimetres, no UVs, rotated and 1e4 from the origin",
            head(CM).no_uvs().rotated_at(1e4),
        ),
    ]
}
