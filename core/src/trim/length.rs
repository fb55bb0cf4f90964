//! A render hair's trimmed length, the shot pass, and the cut.
//!
//! A hair bound to guides with weights `w_i` is their weighted shape scaled
//! by `s` (its groom length). Where each guide rises along its curve
//! parameter at its own rate and meets the cloth at parameter `c_i`, the
//! hair reaches the cloth at `1 / (s sum_i w_i / c_i)`: a weighted harmonic
//! mean, exact for straight guides under a flat cloth, and never longer
//! than the weighted arithmetic mean (which would leave hairs through the
//! cloth between guides that lean differently). A guide that meets nothing
//! counts as meeting at its tip, or at the hair's tip when the hair is the
//! longer (`c_i = max(1, s)`): a hair between a trimmed guide and an
//! untrimmed one is cut as if the untrimmed one reached the cloth just past
//! its tip, a hair with no trimmed guide stays whole, and the length is
//! continuous across a patch (weights vary smoothly).
//!
//! The shot pass keeps each hair's shortest length over every frame of a
//! shot, so a trimmed hair does not grow back and forth as the cloth moves.

use crate::collide::Colliders;
use crate::collide::FIELD_BATCH;
use crate::curve::{cut, WHOLE};
use crate::interp::bind::StrandBinding;
use crate::interp::expand::ExpandJob;
use crate::interp::groom::StrandGroom;
use crate::interp::strand::{EndPoints, MAX_STRAND_POINTS};
use crate::interp::strands::Strands;
use crate::surface::body::Body;
use crate::trim::meet::TrimRecord;
use crate::trim::meet::{first_meet, first_meets};
use crate::Error;
use core::ops::Range;
use glam::Vec3;

/// Fills `lengths` (one per guide of the first `lengths.len()` guides of a
/// frame of `guides` guides of `points` points) with each guide's meet
/// parameter under `records`, infinity where a guide has none (a hair
/// longer than its guide is cut by a guide meeting at its tip, never by one
/// meeting nothing). The records are checked against the whole frame
/// first; on error `lengths` is unchanged. A guide with two records takes
/// the shorter; a record of a guide past `lengths` is left out, so a
/// caller whose strands use only the first guides sizes `lengths` by them,
/// never by a count that comes from a file.
pub fn guide_lengths(
    records: &[TrimRecord],
    guides: usize,
    points: usize,
    lengths: &mut [f32],
) -> Result<(), Error> {
    if lengths.len() > guides {
        return Err(Error::InvalidArgument(
            "more guide lengths than the frame has guides",
        ));
    }
    if !(2..=MAX_STRAND_POINTS).contains(&points) {
        return Err(Error::InvalidArgument("points per guide must be in 2..=64"));
    }
    for (i, r) in records.iter().enumerate() {
        r.check(i, guides, points)?;
    }
    lengths.fill(f32::INFINITY);
    for r in records {
        if let Some(l) = lengths.get_mut(r.guide as usize) {
            *l = l.min(r.length);
        }
    }
    Ok(())
}

/// The length of a hair with `binding` and `groom` under per-guide meet
/// parameters `guides` (see [`guide_lengths`]: infinity for none), stored in 16 bits rounded
/// down, so a stored cut never reaches past the meet.
pub fn hair_length(binding: &StrandBinding, groom: &StrandGroom, guides: &[f32]) -> u16 {
    let s = groom.length;
    if s <= 0.0 {
        return WHOLE;
    }
    let untrimmed = s.max(1.0);
    let (mut rate, mut weight, mut trimmed) = (0.0f32, 0.0f32, false);
    for k in 0..binding.count as usize {
        let w = binding.weights[k];
        if w > 0.0 {
            let c = guides[binding.guides[k] as usize];
            trimmed |= c.is_finite();
            rate += w / c.min(untrimmed);
            weight += w;
        }
    }
    // the weights sum to 1 only within WEIGHT_SUM_TOLERANCE: the mean is
    // over the weights as they are
    if !trimmed {
        return WHOLE;
    }
    let f = weight / (s * rate);
    (f.min(1.0) * WHOLE as f32) as u16
}

/// The shot pass, one frame at a time: each of `strands`' stored lengths
/// in `lengths` becomes the shorter of itself and the strand's length under
/// this frame's per-guide parameters `guides`. Start a shot with every
/// length [`WHOLE`]; the result does not depend on the order of frames.
///
/// Stops at the shorter of `strands` and `lengths`.
///
/// # Panics
/// When a binding's guide is past `guides` (strand records checked against
/// the frame's guide count do not).
pub fn shortest(strands: &Strands, guides: &[f32], lengths: &mut [u16]) {
    for ((b, g), l) in strands.bindings.iter().zip(strands.grooms).zip(lengths) {
        *l = (*l).min(hair_length(b, g, guides));
    }
}

/// Strands expanded at a time by [`shortest_own`]: a host field hears
/// about as many at once.
const OWN_BATCH: usize = FIELD_BATCH;

/// The shot pass on the hairs themselves, one frame at a time: each strand
/// of `range` of `job` (whose output stride is 16) is expanded, and its
/// stored length in `lengths` (one per strand of the range) becomes the
/// shorter of itself and where the strand's own curve first meets `cloth`
/// or enters one of `colliders`. Exact where the guides' records
/// ([`shortest`]) estimate: an interpolated hair never crosses the cloth
/// before its cut, at any frame of the shot. Costs an expansion and a walk
/// of every segment through the cloth's grid per frame. A cut is checked
/// against the frame that shortens it and the ones after (its respread
/// points must meet nothing there); a second pass over the shot's frames
/// checks every cut against every frame.
///
/// # Panics
/// When `range` is not within the job's strands, `lengths` is shorter than
/// it, or the job's stride is not 16.
pub fn shortest_own(
    job: &ExpandJob,
    range: Range<usize>,
    cloth: Option<&Body>,
    colliders: &Colliders,
    lengths: &mut [u16],
) {
    let params = job.params();
    let (per, n) = (params.output_points(), params.points_per_strand);
    let first = (params.end_points == EndPoints::Pinned) as usize;
    let mut buffer = [[0.0f32; 4]; OWN_BATCH * (MAX_STRAND_POINTS + 2)];
    let mut start = range.start;
    while start < range.end {
        let end = (start + OWN_BATCH).min(range.end);
        let curves = &mut buffer[..(end - start) * per];
        job.run(start..end, bytemuck::cast_slice_mut(curves));
        let point = |k: usize, j: usize| {
            let p = curves[k * per + first + j];
            Vec3::new(p[0], p[1], p[2])
        };
        let mut owns = [WHOLE; OWN_BATCH];
        first_meets(end - start, n, point, cloth, colliders, |k, (_, t)| {
            // a step short of the meet, so rounding cannot put the tip on it
            owns[k] = ((t * WHOLE as f32) as u16).saturating_sub(1);
        });
        for (k, curve) in curves.chunks(per).enumerate() {
            let points = &curve[first..first + n];
            let l = &mut lengths[start - range.start + k];
            let shorter = (*l).min(owns[k]);
            if shorter < WHOLE {
                *l = clear_cut(points, shorter, cloth, colliders);
            }
        }
        start = end;
    }
}

/// Most times [`clear_cut`] shortens a cut whose respread points still
/// meet the cloth.
const CUT_TRIES: usize = 4;

/// `length`, or shorter, so that `points` cut there meet nothing on this
/// frame: the respread points' chords cut the corners of the curve, so a
/// cut short of the curve's meet (this frame's, or an earlier frame's
/// shorter one) can still meet the cloth.
fn clear_cut(
    points: &[[f32; 4]],
    mut length: u16,
    cloth: Option<&Body>,
    colliders: &Colliders,
) -> u16 {
    let n = points.len();
    let mut cut_points = [[0.0f32; 4]; MAX_STRAND_POINTS];
    for _ in 0..CUT_TRIES {
        let trial = &mut cut_points[..n];
        trial.copy_from_slice(points);
        cut(trial, length);
        let at = |j: usize| Vec3::new(trial[j][0], trial[j][1], trial[j][2]);
        match first_meet(n, at, cloth, colliders) {
            Some((_, u)) => length = ((u * length as f32) as u16).saturating_sub(1),
            None => break,
        }
    }
    length
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interp::bind::MAX_NEIGHBOURS;

    fn bound(guides: &[(u32, f32)]) -> StrandBinding {
        let mut b = StrandBinding {
            guides: [0; MAX_NEIGHBOURS],
            weights: [0.0; MAX_NEIGHBOURS],
            count: guides.len() as u32,
            clump: crate::interp::bind::NO_GUIDE,
        };
        for (k, &(g, w)) in guides.iter().enumerate() {
            (b.guides[k], b.weights[k]) = (g, w);
        }
        b
    }

    fn groom(length: f32) -> StrandGroom {
        StrandGroom {
            length,
            ..StrandGroom::default()
        }
    }

    #[test]
    fn a_hair_is_cut_by_its_guides_weighted() {
        let guides = [0.5, f32::INFINITY, 0.25];
        let one = bound(&[(0, 1.0)]);
        let two = bound(&[(0, 0.5), (1, 0.5)]);
        let close = |l: u16, f: f32| (l as f32 / WHOLE as f32 - f).abs() < 1e-4;
        assert!(close(hair_length(&one, &groom(1.0), &guides), 0.5));
        // a hair twice the guide reaches the meet halfway
        assert!(close(hair_length(&one, &groom(2.0), &guides), 0.25));
        // a hair shorter than the guide's meet is whole
        assert_eq!(hair_length(&one, &groom(0.4), &guides), WHOLE);
        // the weighted harmonic mean; an untrimmed guide meets at its tip
        assert!(close(hair_length(&two, &groom(1.0), &guides), 2.0 / 3.0));
        assert!(close(hair_length(&two, &groom(0.5), &guides), 1.0));
        let three = bound(&[(0, 0.5), (2, 0.5)]);
        assert!(close(hair_length(&three, &groom(1.0), &guides), 1.0 / 3.0));
        // no guide trimmed: whole, whatever the groom length
        assert_eq!(
            hair_length(&bound(&[(1, 1.0)]), &groom(3.0), &guides),
            WHOLE
        );
        assert_eq!(hair_length(&bound(&[]), &groom(1.0), &guides), WHOLE);
    }

    #[test]
    fn the_shot_pass_keeps_the_shortest_in_any_frame_order() {
        let roots = [crate::Root::default(); 2];
        let bindings = [bound(&[(0, 1.0)]), bound(&[(0, 0.5), (1, 0.5)])];
        let grooms = [groom(1.0), groom(1.0)];
        let strands = Strands {
            roots: &roots,
            bindings: &bindings,
            grooms: &grooms,
        };
        let frames = [[0.8f32, f32::INFINITY], [0.3, 0.9], [f32::INFINITY, 0.2]];
        let run = |order: &[usize]| {
            let mut lengths = [WHOLE; 2];
            for &f in order {
                shortest(&strands, &frames[f], &mut lengths);
            }
            lengths
        };
        let forward = run(&[0, 1, 2]);
        assert_eq!(forward, run(&[2, 0, 1]));
        assert_eq!(
            forward[0],
            hair_length(&bindings[0], &grooms[0], &frames[1])
        );
        assert_eq!(
            forward[1],
            hair_length(&bindings[1], &grooms[1], &frames[2])
        );
    }

    #[test]
    fn records_are_checked_and_the_shorter_kept() {
        let mut lengths = [0.0f32; 3];
        let r = |guide, cv, length| TrimRecord { guide, cv, length };
        guide_lengths(&[r(1, 2, 0.4), r(1, 3, 0.3)], 3, 8, &mut lengths).unwrap();
        assert_eq!(lengths, [f32::INFINITY, 0.3, f32::INFINITY]);
        // a record past the guides asked for counts only in the check
        let mut first = [0.0f32; 2];
        guide_lengths(&[r(1, 2, 0.4), r(4, 3, 0.3)], 5, 8, &mut first).unwrap();
        assert_eq!(first, [f32::INFINITY, 0.4]);
        assert!(guide_lengths(&[], 1, 8, &mut first).is_err());
        for bad in [
            r(3, 1, 0.5),
            r(0, 0, 0.5),
            r(0, 8, 0.5),
            r(0, 1, f32::NAN),
            r(0, 1, 1.5),
        ] {
            let mut untouched = [7.0f32; 3];
            assert!(guide_lengths(&[bad], 3, 8, &mut untouched).is_err());
            assert_eq!(untouched, [7.0; 3]);
        }
    }

    #[test]
    fn a_cut_keeps_the_curve_up_to_its_length() {
        let straight: Vec<[f32; 4]> = (0..8)
            .map(|j| [0.0, 0.0, j as f32, 1.0 - 0.1 * j as f32])
            .collect();
        let mut cut_half = straight.clone();
        cut(&mut cut_half, WHOLE / 2);
        for (k, p) in cut_half.iter().enumerate() {
            let z = 3.5 * k as f32 / 7.0;
            assert!((p[2] - z).abs() < 1e-3, "{k}: {p:?}");
            assert!((p[3] - (1.0 - 0.1 * z)).abs() < 1e-3);
        }
        let mut whole = straight.clone();
        cut(&mut whole, WHOLE);
        assert_eq!(whole, straight);
        let mut none = straight.clone();
        cut(&mut none, 0);
        assert!(none.iter().all(|p| p[..3] == [0.0; 3]));
    }
}
