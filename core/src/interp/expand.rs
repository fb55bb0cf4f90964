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
mod tests;
