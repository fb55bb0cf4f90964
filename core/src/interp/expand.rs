//! Expanding render strands from a posed frame (every frame, any range).
//!
//! Guides are first expressed in their own root frames on the deformed mesh
//! ([`PosedFrame`], once per frame). A strand's points are the weighted
//! average of its guides' local points, shaped by its groom values, and
//! carried back to world space by the strand's own root frame (paper 2.2).
//!
//! An [`ExpandJob`] checks everything once (frame, parameters, strand
//! records or their bounds, the output), then runs any ranges of strands
//! without a further check or failure, on any threads.

use crate::collide::{
    curve_local, field_verdicts, push_out_curve_known, Colliders, FIELD_BATCH, MAX_POINTS,
};
use crate::curve::{cut, WHOLE};
use crate::interp::posed::PosedFrame;
use crate::interp::strand::{strand_n, EndPoints, ExpandParams, Lanes, MAX_STRAND_POINTS};
use crate::interp::strands::{StrandBounds, Strands};
use crate::surface::frame::FaceBasis;
use crate::surface::frame::{self, Frame, FRAME_LANES};
use crate::Error;
use core::ops::Range;
use glam::Vec3;

/// One expansion, checked: a posed frame, strands that fit it, parameters
/// and an output layout. [`ExpandJob::run`] then writes any range of the
/// strands without failing; every range is a pure function of its strands,
/// so any split gives the same bits.
#[derive(Clone, Copy)]
pub struct ExpandJob<'r, 'a> {
    frame: &'r PosedFrame<'a>,
    strands: Strands<'r>,
    params: ExpandParams,
    stride: usize,
    trim: Option<&'r [u16]>,
    push: Option<Push<'r>>,
}

/// The strands a user mask selects, and the colliders they are pushed out of.
#[derive(Clone, Copy)]
struct Push<'r> {
    mask: &'r [u8],
    colliders: &'r Colliders<'r>,
}

impl<'r, 'a> ExpandJob<'r, 'a> {
    /// Checks that `frame` is posed for `params`, that `strands` (whose
    /// records [`StrandBounds::new`] checked, giving `bounds`) fit its mesh
    /// and guides, and that `out_len` bytes hold every strand's curve at
    /// `stride` bytes per point.
    pub fn new(
        frame: &'r PosedFrame<'a>,
        strands: Strands<'r>,
        bounds: &StrandBounds,
        params: &ExpandParams,
        out_len: usize,
        stride: usize,
    ) -> Result<Self, Error> {
        frame.check_params(params)?;
        if strands.bindings.len() < strands.len() || strands.grooms.len() < strands.len() {
            return Err(Error::InvalidArgument(
                "bindings and grooms must cover every strand",
            ));
        }
        bounds.fits(frame.mesh().triangle_count(), frame.guide_count())?;
        check_output(strands.len(), params, out_len, stride)?;
        Ok(ExpandJob {
            frame,
            strands,
            params: *params,
            stride,
            trim: None,
            push: None,
        })
    }

    /// The same job, each strand that `mask` selects (one byte per strand,
    /// nonzero: selected) pushed out of `colliders` after it is expanded
    /// (and cut): rotated about its root as guides are (paper 3.3: render
    /// hairs in user regions, which interpolation can leave inside a
    /// collider even when every guide is clear).
    pub fn pushed(self, mask: &'r [u8], colliders: &'r Colliders<'r>) -> Result<Self, Error> {
        if mask.len() < self.strands.len() {
            return Err(Error::OutputTooSmall {
                needed: self.strands.len(),
                available: mask.len(),
            });
        }
        colliders.check()?;
        Ok(ExpandJob {
            push: Some(Push { mask, colliders }),
            ..self
        })
    }

    /// The same job, each strand cut at its stored length in `lengths`
    /// (one per strand, [`WHOLE`] for none; see [`crate::trim::length`]).
    pub fn trimmed(self, lengths: &'r [u16]) -> Result<Self, Error> {
        if lengths.len() < self.strands.len() {
            return Err(Error::OutputTooSmall {
                needed: self.strands.len(),
                available: lengths.len(),
            });
        }
        Ok(ExpandJob {
            trim: Some(lengths),
            ..self
        })
    }

    /// Number of strands.
    pub fn len(&self) -> usize {
        self.strands.len()
    }

    /// True when there is no strand.
    pub fn is_empty(&self) -> bool {
        self.strands.is_empty()
    }

    /// The expansion parameters.
    pub fn params(&self) -> &ExpandParams {
        &self.params
    }

    /// Output bytes between one strand's first point and the next's.
    pub fn bytes_per_strand(&self) -> usize {
        self.params.output_points() * self.stride
    }

    /// Writes the curves of the strands in `range` into `out`, which starts
    /// at the range's first point: `output_points()` float4 (x, y, z,
    /// radius) per strand, `stride` bytes apart, strand after strand.
    ///
    /// # Panics
    /// When `range` is not within the strands or `out` is too short for it.
    pub fn run(&self, range: Range<usize>, out: &mut [u8]) {
        expand_kernel(self, range, out);
    }

    /// [`ExpandJob::run`] compiled for AVX2: the same operations in the same
    /// order (no fused multiply-add), so the same bits, in wider registers.
    ///
    /// # Safety
    /// The CPU must have AVX2: the host checks first (for example with
    /// `is_x86_feature_detected!("avx2")`); outside an AVX2 context the call
    /// needs `unsafe`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    pub fn run_avx2(&self, range: Range<usize>, out: &mut [u8]) {
        expand_kernel(self, range, out);
    }
}

/// Checks `strands` and writes all their curves into `out` (see
/// [`ExpandJob`]): the one-call form. Nothing is written on error.
pub fn expand(
    frame: &PosedFrame,
    strands: &Strands,
    params: &ExpandParams,
    out: &mut [u8],
    stride: usize,
) -> Result<(), Error> {
    let bounds = StrandBounds::new(strands)?;
    let job = ExpandJob::new(frame, *strands, &bounds, params, out.len(), stride)?;
    job.run(0..job.len(), out);
    Ok(())
}

/// Checks that `out_len` bytes hold the curves of `count` strands at `stride`.
fn check_output(
    count: usize,
    params: &ExpandParams,
    out_len: usize,
    stride: usize,
) -> Result<(), Error> {
    if stride < 16 {
        return Err(Error::BadStride {
            what: "curve points",
        });
    }
    let needed = count
        .checked_mul(params.output_points())
        .and_then(|total| total.checked_sub(1))
        .map_or(Some(0), |last| {
            last.checked_mul(stride).and_then(|b| b.checked_add(16))
        })
        .ok_or(Error::InvalidArgument("curve output size overflows"))?;
    if out_len < needed {
        return Err(Error::OutputTooSmall {
            needed,
            available: out_len,
        });
    }
    Ok(())
}

/// The body of [`ExpandJob::run`], inlined whole into each entry so that
/// the AVX2 entry compiles every per-strand step for AVX2.
#[inline(always)]
fn expand_kernel(job: &ExpandJob, range: Range<usize>, out: &mut [u8]) {
    let strands = &job.strands.range(range.clone());
    let trim = job.trim.map(|t| &t[range.clone()]);
    let push = job.push.map(|p| Push {
        mask: &p.mask[range],
        ..p
    });
    let (frame, params, stride) = (job.frame, &job.params, job.stride);
    // the common counts get loops of known length (see `strand`), chosen
    // once per call rather than per strand
    match params.points_per_strand {
        8 => fill_all::<8>(frame, strands, (trim, push), params, out, stride),
        16 => fill_all::<16>(frame, strands, (trim, push), params, out, stride),
        32 => fill_all::<32>(frame, strands, (trim, push), params, out, stride),
        _ => fill_all::<0>(frame, strands, (trim, push), params, out, stride),
    }
}

/// [`expand_kernel`] for `N` points per strand (0: any).
#[inline(always)]
fn fill_all<const N: usize>(
    guides: &PosedFrame,
    strands: &Strands,
    (trim, push): (Option<&[u16]>, Option<Push>),
    params: &ExpandParams,
    out: &mut [u8],
    stride: usize,
) {
    let per = params.output_points();
    let mut filler = Filler {
        strands,
        trim,
        push,
        guides,
        params,
        lanes: Lanes::new(params.points_per_strand),
        basis: None,
        frames: [Frame::default(); FRAME_LANES],
    };
    let n = strands.len();
    if filler.push.is_some_and(|p| p.colliders.field.is_some()) {
        return fill_batched::<N>(&mut filler, n, per, out, stride);
    }
    // packed float4 output is written in place
    if stride == 16 {
        if let Ok(all) = bytemuck::try_cast_slice_mut::<u8, [f32; 4]>(&mut out[..n * per * 16]) {
            for (s, curve) in all.chunks_exact_mut(per).enumerate() {
                filler.fill::<N>(s, curve);
            }
            return;
        }
    }
    let mut buffer = [[0.0f32; 4]; MAX_STRAND_POINTS + 2];
    for s in 0..n {
        filler.fill::<N>(s, &mut buffer[..per]);
        let region = &mut out[s * per * stride..];
        for (j, p) in buffer[..per].iter().enumerate() {
            region[j * stride..j * stride + 16].copy_from_slice(bytemuck::bytes_of(p));
        }
    }
}

/// [`fill_all`] for strands pushed out of colliders with a host field:
/// [`FIELD_BATCH`] strands at a time are made and cut, the field asked
/// once whether each strand to push is clear, then each pushed and
/// written. The bits of [`Filler::fill`] strand by strand.
#[inline(never)]
fn fill_batched<const N: usize>(
    filler: &mut Filler,
    n: usize,
    per: usize,
    out: &mut [u8],
    stride: usize,
) {
    let mut curves = [[[0.0f32; 4]; MAX_STRAND_POINTS + 2]; FIELD_BATCH];
    let mut frames = [Frame::default(); FIELD_BATCH];
    let mut pushed = [false; FIELD_BATCH];
    let mut locals = [[Vec3::ZERO; MAX_POINTS]; FIELD_BATCH];
    let mut counts = [0usize; FIELD_BATCH];
    let mut verdicts = [None; FIELD_BATCH];
    for start in (0..n).step_by(FIELD_BATCH) {
        let batch = FIELD_BATCH.min(n - start);
        for i in 0..batch {
            let curve = &mut curves[i][..per];
            pushed[i] = filler.fill_cut::<N>(start + i, curve);
            frames[i] = filler.frames[(start + i) % FRAME_LANES];
            if pushed[i] {
                let points = filler.pushed_points(curve);
                counts[i] = curve_local(&frames[i], points, &mut locals[i]).0;
            }
        }
        let colliders = filler.push.map(|p| p.colliders);
        field_verdicts(
            colliders.unwrap_or(&Colliders::default()),
            |i| pushed[i].then(|| (frames[i], &locals[i][..counts[i]])),
            &mut verdicts[..batch],
        );
        for i in 0..batch {
            let curve = &mut curves[i][..per];
            if pushed[i] {
                filler.push_and_pin(curve, &frames[i], verdicts[i]);
            }
            let region = &mut out[(start + i) * per * stride..];
            for (j, p) in curve.iter().enumerate() {
                region[j * stride..j * stride + 16].copy_from_slice(bytemuck::bytes_of(p));
            }
        }
    }
}

/// What [`expand_kernel`] carries from strand to strand.
struct Filler<'r, 'a> {
    strands: &'r Strands<'r>,
    /// Stored lengths of the strands, when trimmed.
    trim: Option<&'r [u16]>,
    /// The strands to push out, and the colliders.
    push: Option<Push<'r>>,
    guides: &'r PosedFrame<'a>,
    params: &'r ExpandParams,
    lanes: Lanes,
    basis: Option<(u32, FaceBasis)>,
    /// Root frames of the current block of strands.
    frames: [Frame; FRAME_LANES],
}

impl Filler<'_, '_> {
    /// Writes strand `s` to `curve`. Strands are filled in order: the
    /// frames of a block are computed at its first strand, so that their
    /// square-root chains overlap (see `frame::frames`).
    #[inline(always)]
    fn fill<const N: usize>(&mut self, s: usize, curve: &mut [[f32; 4]]) {
        if self.fill_cut::<N>(s, curve) {
            self.push_and_pin(curve, &self.frames[s % FRAME_LANES], None);
        }
    }

    /// [`fill`](Self::fill) up to the push-out: strand `s` made, cut and
    /// (unless it is to be pushed) pinned into `curve`, its root frame in
    /// `self.frames[s % FRAME_LANES]`; true when it is to be pushed
    /// ([`push_and_pin`](Self::push_and_pin) finishes it then).
    #[inline(always)]
    fn fill_cut<const N: usize>(&mut self, s: usize, curve: &mut [[f32; 4]]) -> bool {
        let slot = s % FRAME_LANES;
        if slot == 0 {
            let roots = &self.strands.roots[s..];
            let tangents = self.guides.tangents();
            frame::frames(
                self.guides.mesh(),
                tangents,
                roots,
                &mut self.basis,
                &mut self.frames,
            );
        }
        strand_n::<N>(
            &self.frames[slot],
            &self.strands.bindings[s],
            &self.strands.grooms[s],
            self.guides,
            self.params,
            &mut self.lanes,
            curve,
        );
        let length = self.trim.map_or(WHOLE, |t| t[s]);
        let push = self.push.is_some_and(|p| p.mask[s] != 0);
        if length == WHOLE && !push {
            return false;
        }
        let pinned = self.params.end_points == EndPoints::Pinned;
        let n = self.params.points_per_strand;
        cut(&mut curve[pinned as usize..pinned as usize + n], length);
        if !push && pinned {
            curve[0] = curve[1];
            curve[n + 1] = curve[n];
        }
        push
    }

    /// The points of a strand's curve that its push-out moves (the pinned
    /// ends left out).
    fn pushed_points<'c>(&self, curve: &'c [[f32; 4]]) -> &'c [[f32; 4]] {
        let pinned = self.params.end_points == EndPoints::Pinned;
        &curve[pinned as usize..pinned as usize + self.params.points_per_strand]
    }

    /// The rest of [`fill`](Self::fill) for a strand [`fill_cut`](Self::fill_cut)
    /// left to push: its push-out on `frame` told the host field's answer
    /// `field`, then its pinned ends.
    fn push_and_pin(&self, curve: &mut [[f32; 4]], frame: &Frame, field: Option<bool>) {
        let Some(p) = self.push else {
            return;
        };
        let pinned = self.params.end_points == EndPoints::Pinned;
        let n = self.params.points_per_strand;
        let points = &mut curve[pinned as usize..pinned as usize + n];
        push_out_curve_known(p.colliders, frame, points, field);
        if pinned {
            curve[0] = curve[1];
            curve[n + 1] = curve[n];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arena::{Arena, ArenaLayout};
    use crate::guides::CvLayout;
    use crate::guides::Guides;
    use crate::interp::bind::StrandBinding;
    use crate::interp::bind::{bind, BindParams};
    use crate::interp::groom::GroomMaps;
    use crate::interp::groom::StrandGroom;
    use crate::interp::strand::EndPoints;
    use crate::testmesh::{bumpy_plane, graded_plane, roots, straight_guides, TestMesh};
    use crate::Strided;
    use crate::{Mesh, Root};
    use glam::Vec3;
    use proptest::prelude::*;

    const CVS: usize = 8;

    struct Scene {
        m: TestMesh,
        guide_roots: Vec<Root>,
        guide_points: Vec<[f32; 3]>,
        strands: Vec<Root>,
    }

    impl Scene {
        fn plane(guides: u32, strands: u32) -> Scene {
            Scene::on(graded_plane(16, 1.0), guides, strands)
        }

        fn on(m: TestMesh, guides: u32, strands: u32) -> Scene {
            let guide_roots = roots(m.mesh(), guides, 5);
            let guide_points = straight_guides(&m.mesh(), &guide_roots, CVS, 0.1);
            let strands = roots(m.mesh(), strands, 9);
            Scene {
                m,
                guide_roots,
                guide_points,
                strands,
            }
        }

        fn guides(&self) -> Guides<'_> {
            Guides {
                roots: &self.guide_roots,
                points: Strided::from_slice(&self.guide_points),
                layout: CvLayout::Fixed(CVS),
            }
        }

        fn bind(&self, params: &BindParams) -> Vec<StrandBinding> {
            let mut buf =
                vec![
                    0u8;
                    crate::interp::bind::required_bytes(&self.m.mesh(), self.guide_roots.len())
                        .unwrap()
                ];
            let mut out = vec![StrandBinding::default(); self.strands.len()];
            bind(
                &self.m.mesh(),
                &self.guides(),
                &self.strands,
                params,
                &mut Arena::new(&mut buf),
                &mut out,
            )
            .unwrap();
            out
        }

        /// Runs `f` with this scene's guides prepared for `n` points.
        fn prepared<R>(&self, n: usize, f: impl FnOnce(&PosedFrame) -> R) -> R {
            let mesh = self.m.mesh();
            let mut layout = ArenaLayout::new();
            PosedFrame::layout(&mut layout, self.m.p.len(), self.guide_roots.len(), n);
            let mut buf = vec![0u8; layout.bytes()];
            let mut arena = Arena::new(&mut buf);
            let prepared = PosedFrame::with_guides(mesh, &self.guides(), n, &mut arena).unwrap();
            f(&prepared)
        }

        fn expand(
            &self,
            bindings: &[StrandBinding],
            grooms: &[StrandGroom],
            params: &ExpandParams,
            chunks: usize,
        ) -> Vec<[f32; 4]> {
            self.prepared(params.points_per_strand, |prepared| {
                let per = params.output_points();
                let n = self.strands.len();
                let mut out = vec![[0.0f32; 4]; n * per];
                for c in 0..chunks {
                    let r = c * n / chunks..(c + 1) * n / chunks;
                    let bytes: &mut [u8] =
                        bytemuck::cast_slice_mut(&mut out[r.start * per..r.end * per]);
                    let all = Strands {
                        roots: &self.strands,
                        bindings,
                        grooms,
                    };
                    expand(prepared, &all.range(r), params, bytes, 16).unwrap();
                }
                out
            })
        }
    }

    fn plain_grooms(n: usize) -> Vec<StrandGroom> {
        vec![
            StrandGroom {
                length: 1.0,
                root_radius: 0.001,
                tip_radius: 0.0005,
                ..StrandGroom::default()
            };
            n
        ]
    }

    /// Strand `i`'s groom with every shaping value set (no clump): bend,
    /// a kink whose phase turns with `i`, and a sideways lift.
    fn styled(i: usize) -> StrandGroom {
        StrandGroom {
            length: 0.9,
            root_radius: 0.002,
            tip_radius: 0.0005,
            bend: 0.2,
            kink_amplitude: 0.05,
            kink_frequency: 3.0,
            kink_phase: [libm::cosf(i as f32), libm::sinf(i as f32)],
            lift: [0.1 * libm::sinf(i as f32), 0.0],
            ..StrandGroom::default()
        }
    }

    fn raw(n: usize) -> ExpandParams {
        ExpandParams {
            points_per_strand: n,
            end_points: EndPoints::Raw,
            orphan_length: 0.1,
            width_scale: 1.0,
        }
    }

    #[test]
    fn identical_bits_for_any_chunking() {
        let s = Scene::plane(200, 3000);
        let b = s.bind(&BindParams::default());
        let mut grooms = plain_grooms(s.strands.len());
        let maps = GroomMaps {
            kink_amplitude: crate::ScalarMap::Constant(0.1),
            clump: crate::ScalarMap::Constant(0.5),
            bend: crate::ScalarMap::Constant(0.2),
            ..GroomMaps::default()
        };
        maps.evaluate(&s.m.mesh(), &s.strands, 3, &mut grooms)
            .unwrap();
        let one = s.expand(&b, &grooms, &raw(CVS), 1);
        for chunks in [2, 7] {
            let other = s.expand(&b, &grooms, &raw(CVS), chunks);
            assert!(bytemuck::cast_slice::<_, u8>(&one) == bytemuck::cast_slice::<_, u8>(&other));
        }
        assert!(one
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite()) && p[3] >= 0.0));
    }

    #[test]
    fn a_lift_too_small_to_square_turns_nothing() {
        let s = Scene::plane(100, 400);
        let b = s.bind(&BindParams::default());
        let plain = plain_grooms(s.strands.len());
        let tiny: Vec<StrandGroom> = plain
            .iter()
            .map(|g| StrandGroom {
                lift: [1e-25, -1e-30],
                ..*g
            })
            .collect();
        assert_eq!(
            s.expand(&b, &plain, &raw(CVS), 1),
            s.expand(&b, &tiny, &raw(CVS), 1)
        );
    }

    #[test]
    fn roots_sit_on_the_surface_and_pinned_ends_repeat() {
        let s = Scene::plane(150, 500);
        let b = s.bind(&BindParams::default());
        let params = ExpandParams {
            end_points: EndPoints::Pinned,
            ..raw(CVS)
        };
        let out = s.expand(&b, &plain_grooms(s.strands.len()), &params, 1);
        let per = params.output_points();
        for (i, r) in s.strands.iter().enumerate() {
            let root = s.m.mesh().point(r.face as usize, r.u, r.v);
            let c = &out[i * per..(i + 1) * per];
            assert!(Vec3::new(c[1][0], c[1][1], c[1][2]).distance(root) < 1e-5);
            assert_eq!(c[0], c[1]);
            assert_eq!(c[per - 1], c[per - 2]);
            assert!(c[per - 1][2] > 0.0, "tip above the plane");
        }
    }

    #[test]
    fn curves_follow_a_moving_body_without_swimming() {
        // the character walks and turns: the mesh and the posed guides move
        // rigidly; every curve must move with them, shape, kink, clump and
        // lift included (frames come from the triangles, not from world axes)
        let s = Scene::plane(60, 400);
        let b = s.bind(&BindParams::default());
        let grooms: Vec<StrandGroom> = (0..s.strands.len())
            .map(|i| StrandGroom {
                length: 0.8 + 0.001 * i as f32,
                clump: 0.3,
                ..styled(i)
            })
            .collect();
        let params = ExpandParams {
            end_points: EndPoints::Pinned,
            ..raw(CVS)
        };
        let rest = s.expand(&b, &grooms, &params, 1);
        let turn = glam::Quat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 2.3);
        let walk = Vec3::new(3.0, -1.0, 0.5);
        let moved = |p: &[f32; 3]| (turn * Vec3::from(*p) + walk).into();
        let posed = Scene {
            m: TestMesh {
                p: s.m.p.iter().map(moved).collect(),
                ..s.m.clone()
            },
            guide_roots: s.guide_roots.clone(),
            guide_points: s.guide_points.iter().map(moved).collect(),
            strands: s.strands.clone(),
        };
        let out = posed.expand(&b, &grooms, &params, 1);
        let mut worst = 0.0f32;
        for (a, o) in rest.iter().zip(&out) {
            let expect = turn * Vec3::new(a[0], a[1], a[2]) + walk;
            worst = worst.max(expect.distance(Vec3::new(o[0], o[1], o[2])));
            assert_eq!(a[3], o[3], "radius");
        }
        // float rounding at coordinates of a few units, not a swim
        assert!(worst < 2e-5, "curves moved {worst} away from the body");
    }

    #[test]
    fn each_groom_value_shapes_the_curve_as_documented() {
        // on a curved skin, every groom value against the plain curve:
        // length scales the root-relative shape, bend moves point j by
        // bend L t^2 along the root tangent, kink by kink L t in the tangent
        // plane turning kink_frequency waves over the strand from the
        // strand's phase, clump pulls point j toward the clump guide by
        // clump t, widths run linearly from root to tip
        let s = Scene::on(bumpy_plane(16), 60, 300);
        let b = s.bind(&BindParams::default());
        let n = s.strands.len();
        let phase = |i: usize| 0.7 * i as f32;
        let plain = StrandGroom {
            length: 1.0,
            root_radius: 0.002,
            tip_radius: 0.0005,
            kink_frequency: 2.5,
            ..StrandGroom::default()
        };
        let with = |f: &dyn Fn(&mut StrandGroom)| {
            let grooms: Vec<StrandGroom> = (0..n)
                .map(|i| {
                    let (sin, cos) = libm::sincosf(phase(i));
                    let mut g = StrandGroom {
                        kink_phase: [cos, sin],
                        ..plain
                    };
                    f(&mut g);
                    g
                })
                .collect();
            s.expand(&b, &grooms, &raw(CVS), 1)
        };
        let base = with(&|_| {});
        let long = with(&|g| g.length = 1.5);
        let bent = with(&|g| g.bend = 0.3);
        let kinked = with(&|g| g.kink_amplitude = 0.05);
        let clumped = with(&|g| g.clump = 0.6);
        let at = |c: &[[f32; 4]], i: usize, j: usize| Vec3::from_slice(&c[i * CVS + j][..3]);
        let delta = core::f32::consts::TAU * 2.5 / (CVS - 1) as f32;
        let close = |a: Vec3, e: Vec3, what: &str, i: usize, j: usize| {
            assert!(
                a.distance(e) < 2e-5,
                "{what}: strand {i} point {j}: {a} vs {e}"
            );
        };
        // an orphan (no guide passes the gates, here on a steep bump) has no
        // clump centre; the clump check needs nearly every strand bound
        let orphans = b
            .iter()
            .filter(|x| x.clump == crate::interp::bind::NO_GUIDE)
            .count();
        assert!(orphans * 100 <= n, "{orphans} orphans of {n}");
        s.prepared(CVS, |prepared| {
            for (i, r) in s.strands.iter().enumerate() {
                let f = prepared.root_frame(r.face as usize, r.u, r.v);
                let root = at(&base, i, 0);
                let len = at(&base, i, CVS - 1).distance(root);
                assert!(len > 0.05, "strand {i} has length {len}");
                for j in 0..CVS {
                    let t = j as f32 / (CVS - 1) as f32;
                    let p = at(&base, i, j);
                    let radius = base[i * CVS + j][3];
                    assert!(
                        (radius - (0.002 - 0.0015 * t)).abs() < 1e-7,
                        "radius {radius}"
                    );
                    close(at(&long, i, j) - root, (p - root) * 1.5, "length", i, j);
                    close(at(&bent, i, j), p + f.t * (0.3 * len * t * t), "bend", i, j);
                    let (sin, cos) = libm::sincosf(phase(i) + j as f32 * delta);
                    let wave = (f.t * sin + f.b * cos) * (0.05 * len * t);
                    close(at(&kinked, i, j), p + wave, "kink", i, j);
                    if b[i].clump == crate::interp::bind::NO_GUIDE {
                        continue;
                    }
                    let c = prepared.world(b[i].clump as usize);
                    let centre = Vec3::new(c[j], c[CVS + j], c[2 * CVS + j]);
                    close(
                        at(&clumped, i, j),
                        p + (centre - p) * (0.6 * t),
                        "clump",
                        i,
                        j,
                    );
                }
            }
        });
    }

    #[test]
    fn curves_keep_their_shape_on_a_bending_body() {
        // the skin rolls around a cylinder (a bend, not a rigid motion) and
        // each posed guide rides on its root, keeping its shape in its root
        // frame: every strand must keep its shape in its own root frame,
        // bend, kink and lift included (clump is left out: it pulls toward
        // the guides' world points, which the bend moves apart)
        let mut flat = graded_plane(16, 1.0);
        flat.n = vec![[0.0, 0.0, 1.0]; flat.p.len()];
        let s = Scene::on(flat, 60, 400);
        let b = s.bind(&BindParams::default());
        let grooms: Vec<StrandGroom> = (0..s.strands.len())
            .map(|i| StrandGroom {
                lift: [0.1 * libm::sinf(i as f32), 0.05],
                ..styled(i)
            })
            .collect();
        let params = raw(CVS);
        let rest = s.expand(&b, &grooms, &params, 1);
        let radius = 0.4;
        let rolled = |p: &[f32; 3]| {
            let (sin, cos) = libm::sincosf(p[0] / radius);
            [(radius + p[2]) * sin, p[1], (radius + p[2]) * cos - radius]
        };
        let bent = TestMesh {
            p: s.m.p.iter().map(rolled).collect(),
            n: s.m
                .p
                .iter()
                .map(|p| {
                    let (sin, cos) = libm::sincosf(p[0] / radius);
                    [sin, 0.0, cos]
                })
                .collect(),
            ..s.m.clone()
        };
        let frames = |scene: &Scene, roots: &[Root]| {
            scene.prepared(CVS, |prepared| {
                roots
                    .iter()
                    .map(|r| prepared.root_frame(r.face as usize, r.u, r.v))
                    .collect::<Vec<_>>()
            })
        };
        let mut posed = Scene {
            m: bent,
            guide_roots: s.guide_roots.clone(),
            guide_points: s.guide_points.clone(),
            strands: s.strands.clone(),
        };
        let (rest_guides, bent_guides) =
            (frames(&s, &s.guide_roots), frames(&posed, &s.guide_roots));
        for (g, points) in posed.guide_points.chunks_mut(CVS).enumerate() {
            for p in points {
                *p = bent_guides[g]
                    .to_world(rest_guides[g].to_local(Vec3::from(*p)))
                    .into();
            }
        }
        let out = posed.expand(&b, &grooms, &params, 1);
        let (rest_frames, bent_frames) = (frames(&s, &s.strands), frames(&posed, &s.strands));
        let mut worst = 0.0f32;
        for (i, (a, o)) in rest.chunks(CVS).zip(out.chunks(CVS)).enumerate() {
            for (p, q) in a.iter().zip(o) {
                let before = rest_frames[i].to_local(Vec3::from_slice(&p[..3]));
                let after = bent_frames[i].to_local(Vec3::from_slice(&q[..3]));
                worst = worst.max(before.distance(after));
                assert_eq!(p[3], q[3], "radius");
            }
        }
        assert!(
            worst < 2e-5,
            "strands changed shape by {worst} in their frames"
        );
        // and the skin did bend under them: the frames turned by up to 2.5 rad
        let turn = rest_frames
            .iter()
            .zip(&bent_frames)
            .map(|(a, b)| a.n.angle_between(b.n));
        assert!(turn.fold(0.0f32, f32::max) > 2.0);
    }

    /// Roots along the segment y = 0.37 + 0.1 x, x in [0.1, 0.9], on the plane.
    fn path(mesh: &Mesh, steps: u32) -> Vec<Root> {
        (0..steps)
            .map(|i| {
                let x = 0.1 + 0.8 * i as f32 / steps as f32;
                let p = Vec3::new(x, 0.37 + 0.1 * x, 0.0);
                let bary = |f: usize| {
                    let [a, b, c] = mesh.corners(f);
                    let (e1, e2, d) = (b - a, c - a, p - a);
                    let det = e1.x * e2.y - e1.y * e2.x;
                    (
                        (d.x * e2.y - d.y * e2.x) / det,
                        (e1.x * d.y - e1.y * d.x) / det,
                    )
                };
                let face = (0..mesh.triangle_count())
                    .find(|&f| {
                        let (u, v) = bary(f);
                        u >= -1e-6 && v >= -1e-6 && u + v <= 1.0 + 1e-6
                    })
                    .unwrap();
                let (u, v) = bary(face);
                Root {
                    face: face as u32,
                    u,
                    v,
                    id: i,
                    rank: i,
                }
            })
            .collect()
    }

    /// Largest change of root-relative shape between consecutive path roots.
    fn largest_step_change(s: &Scene, steps: u32) -> f32 {
        let strands = path(&s.m.mesh(), steps);
        let scene = Scene {
            m: s.m.clone(),
            guide_roots: s.guide_roots.clone(),
            guide_points: s.guide_points.clone(),
            strands,
        };
        let fixed = BindParams {
            min_neighbours: 4,
            max_neighbours: 4,
            ..BindParams::default()
        };
        let b = scene.bind(&fixed);
        let out = scene.expand(&b, &plain_grooms(steps as usize), &raw(CVS), 1);
        let rel = |c: &[[f32; 4]], j: usize| {
            Vec3::new(c[j][0] - c[0][0], c[j][1] - c[0][1], c[j][2] - c[0][2])
        };
        let mut worst = 0.0f32;
        for i in 1..steps as usize {
            let (p, q) = (&out[(i - 1) * CVS..i * CVS], &out[i * CVS..(i + 1) * CVS]);
            for j in 0..CVS {
                worst = worst.max(rel(p, j).distance(rel(q, j)));
            }
        }
        worst
    }

    /// Refining the path 8x must shrink the largest change between
    /// neighbouring strands about 8x, to within a constant times the step
    /// (0.8 / steps): a jump (a seam) stays the same size at every
    /// resolution.
    fn assert_shapes_change_continuously(s: &Scene) {
        let coarse = largest_step_change(s, 1000);
        let fine = largest_step_change(s, 8000);
        assert!(
            fine < 0.3 * coarse,
            "largest change {coarse} at 1000 steps, {fine} at 8000 steps"
        );
        assert!(fine < 20.0 * 0.8 / 8000.0, "change {fine} per step");
    }

    #[test]
    fn shapes_change_continuously_along_a_path() {
        // continuous weights: a hard k cutoff would leave a jump
        assert_shapes_change_continuously(&Scene::plane(120, 10));
    }

    #[test]
    fn shapes_change_continuously_on_a_curved_skin() {
        // on a bumpy skin every triangle turns against its neighbours: the
        // root frame's tangent must not jump at triangle edges (a
        // per-triangle tangent turns leaning strands by a fixed angle there)
        assert_shapes_change_continuously(&Scene::on(bumpy_plane(16), 120, 10));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        #[test]
        fn strand_stays_in_its_guides_envelope(seed in 0u64..1000, kmin in 1u32..5, extra in 0u32..4) {
            let s = Scene::plane(80, 300);
            let params = BindParams { min_neighbours: kmin, max_neighbours: kmin + extra, seed, ..BindParams::default() };
            let b = s.bind(&params);
            let out = s.expand(&b, &plain_grooms(s.strands.len()), &raw(CVS), 1);
            s.prepared(CVS, |prepared| {
            for (i, r) in s.strands.iter().enumerate() {
                let frame = prepared.root_frame(r.face as usize, r.u, r.v);
                for j in 0..CVS {
                    let p = out[i * CVS + j];
                    let local = frame.to_local(Vec3::new(p[0], p[1], p[2]));
                    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
                    for k in 0..b[i].count as usize {
                        let l = prepared.local_point(b[i].guides[k] as usize, j);
                        lo = lo.min(l);
                        hi = hi.max(l);
                    }
                    prop_assert!(local.cmpge(lo - 1e-5).all() && local.cmple(hi + 1e-5).all(),
                        "strand {} point {}: {:?} outside {:?}..{:?}", i, j, local, lo, hi);
                }
            }
            Ok(())
            })?;
        }
    }

    #[test]
    fn variable_cv_counts_resample() {
        let s = Scene::plane(60, 200);
        let b = s.bind(&BindParams::default());
        // the same guides stored with offsets give the same curves
        let offsets: Vec<u32> = (0..=s.guide_roots.len() as u32)
            .map(|g| g * CVS as u32)
            .collect();
        let mesh = s.m.mesh();
        let guides = Guides {
            roots: &s.guide_roots,
            points: Strided::from_slice(&s.guide_points),
            layout: CvLayout::Offsets(&offsets),
        };
        let mut buf = vec![0u8; 1 << 20];
        let prepared =
            PosedFrame::with_guides(mesh, &guides, 15, &mut Arena::new(&mut buf)).unwrap();
        let mut out = vec![[0.0f32; 4]; s.strands.len() * 15];
        let grooms = plain_grooms(s.strands.len());
        let strands = Strands {
            roots: &s.strands,
            bindings: &b,
            grooms: &grooms,
        };
        expand(
            &prepared,
            &strands,
            &raw(15),
            bytemuck::cast_slice_mut(&mut out),
            16,
        )
        .unwrap();
        let straight = s.expand(&b, &plain_grooms(s.strands.len()), &raw(CVS), 1);
        for i in 0..s.strands.len() {
            let tip_a = out[i * 15 + 14];
            let tip_b = straight[i * CVS + CVS - 1];
            assert!((0..3).all(|c| (tip_a[c] - tip_b[c]).abs() < 1e-5));
        }
    }

    /// A ball field over the graded plane, in the strands' way.
    struct Ball;

    impl crate::collide::SignedDistance for Ball {
        fn distances(&self, points: &[[f32; 3]], out: &mut [f32]) {
            for (p, d) in points.iter().zip(out) {
                *d = Vec3::from(*p).distance(Vec3::new(0.5, 0.5, 0.06)) - 0.1;
            }
        }
    }

    #[test]
    fn strands_pushed_out_of_a_host_field_in_batches_keep_their_bits() {
        let s = Scene::plane(200, 3000);
        let b = s.bind(&BindParams::default());
        let g = plain_grooms(s.strands.len());
        let strands = Strands {
            roots: &s.strands,
            bindings: &b,
            grooms: &g,
        };
        let bounds = StrandBounds::new(&strands).unwrap();
        let mask: Vec<u8> = (0..s.strands.len()).map(|i| (i % 3 != 0) as u8).collect();
        let trim: Vec<u16> = (0..s.strands.len())
            .map(|i| if i % 5 == 0 { 40_000 } else { WHOLE })
            .collect();
        let ball = Ball;
        let colliders = Colliders {
            field: Some(&ball),
            ..Colliders::default()
        };
        for end_points in [EndPoints::Raw, EndPoints::Pinned] {
            let params = ExpandParams {
                end_points,
                ..raw(CVS)
            };
            let per = params.output_points();
            let n = s.strands.len();
            s.prepared(CVS, |frame| {
                // through the batches, packed and strided
                let mut packed = vec![[0.0f32; 4]; n * per];
                let job = ExpandJob::new(frame, strands, &bounds, &params, n * per * 16, 16)
                    .unwrap()
                    .pushed(&mask, &colliders)
                    .unwrap()
                    .trimmed(&trim)
                    .unwrap();
                job.run(0..n, bytemuck::cast_slice_mut(&mut packed));
                let mut strided = vec![[0.0f32; 5]; n * per];
                let wide = ExpandJob::new(frame, strands, &bounds, &params, n * per * 20, 20)
                    .unwrap()
                    .pushed(&mask, &colliders)
                    .unwrap()
                    .trimmed(&trim)
                    .unwrap();
                wide.run(0..n, bytemuck::cast_slice_mut(&mut strided));
                // strand by strand, each asking the field for itself
                let mut filler = Filler {
                    strands: &strands,
                    trim: Some(&trim),
                    push: Some(Push {
                        mask: &mask,
                        colliders: &colliders,
                    }),
                    guides: frame,
                    params: &params,
                    lanes: Lanes::new(params.points_per_strand),
                    basis: None,
                    frames: [Frame::default(); FRAME_LANES],
                };
                let mut one = vec![[0.0f32; 4]; n * per];
                for (k, curve) in one.chunks_exact_mut(per).enumerate() {
                    filler.fill::<0>(k, curve);
                }
                assert!(packed == one, "{end_points:?}: packed");
                let narrow: Vec<[f32; 4]> =
                    strided.iter().map(|p| [p[0], p[1], p[2], p[3]]).collect();
                assert!(narrow == one, "{end_points:?}: strided");
                let moved = (0..n)
                    .filter(|&k| mask[k] != 0 && trim[k] == WHOLE)
                    .filter(|&k| {
                        let base = filler_free_expand(frame, &strands, &params, k, per);
                        base != one[k * per..(k + 1) * per]
                    })
                    .count();
                assert!(moved > 10, "{moved} strands pushed");
            });
        }
    }

    /// Strand `k` expanded with no trim and no push.
    fn filler_free_expand(
        frame: &PosedFrame,
        strands: &Strands,
        params: &ExpandParams,
        k: usize,
        per: usize,
    ) -> Vec<[f32; 4]> {
        let mut out = vec![[0.0f32; 4]; per];
        let one = strands.range(k..k + 1);
        expand(frame, &one, params, bytemuck::cast_slice_mut(&mut out), 16).unwrap();
        out
    }
}
