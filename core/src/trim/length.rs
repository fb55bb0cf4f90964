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

use crate::interp::bind::StrandBinding;
use crate::interp::groom::StrandGroom;
use crate::interp::strand::MAX_STRAND_POINTS;
use crate::interp::strands::Strands;
use crate::trim::meet::TrimRecord;
use crate::Error;

/// The stored length of a whole (untrimmed) strand.
pub const WHOLE: u16 = u16::MAX;

/// Fills `lengths` (one per guide of a frame of `points` points per guide)
/// with each guide's meet parameter under `records`, infinity where a guide
/// has none (a hair longer than its guide is cut by a guide meeting at its
/// tip, never by one meeting nothing). The records are checked first; on error `lengths` is unchanged.
/// A guide with two records takes the shorter.
pub fn guide_lengths(
    records: &[TrimRecord],
    points: usize,
    lengths: &mut [f32],
) -> Result<(), Error> {
    for (i, r) in records.iter().enumerate() {
        r.check(i, lengths.len(), points)?;
    }
    lengths.fill(f32::INFINITY);
    for r in records {
        let l = &mut lengths[r.guide as usize];
        *l = l.min(r.length);
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
    let mut rate = 0.0f32;
    for k in 0..binding.count as usize {
        let w = binding.weights[k];
        if w > 0.0 {
            rate += w / guides[binding.guides[k] as usize].min(untrimmed);
        }
    }
    // an orphan has no rate, and an infinite length
    let f = 1.0 / (s * rate);
    (f.min(1.0) * WHOLE as f32) as u16
}

/// The shot pass, one frame at a time: each of `strands`' stored lengths
/// in `lengths` becomes the shorter of itself and the strand's length under
/// this frame's per-guide parameters `guides`. Start a shot with every
/// length [`WHOLE`]; the result does not depend on the order of frames.
///
/// # Panics
/// When `lengths` is shorter than `strands` or a binding's guide is past
/// `guides` (strand records checked against the frame's guide count do not).
pub fn shortest(strands: &Strands, guides: &[f32], lengths: &mut [u16]) {
    for ((b, g), l) in strands.bindings.iter().zip(strands.grooms).zip(lengths) {
        *l = (*l).min(hair_length(b, g, guides));
    }
}

/// Cuts an expanded curve's `points` (evenly spaced along the strand) at
/// stored length `length`: the points are respread over the kept part, so
/// the count stays and the kept part keeps its shape and radii.
pub(crate) fn cut(points: &mut [[f32; 4]], length: u16) {
    let n = points.len();
    if length == WHOLE || n < 2 {
        return;
    }
    let mut whole = [[0.0f32; 4]; MAX_STRAND_POINTS];
    whole[..n].copy_from_slice(points);
    let f = length as f32 / WHOLE as f32;
    for (k, p) in points.iter_mut().enumerate() {
        let u = f * k as f32;
        let i = (u as usize).min(n - 2);
        let a = u - i as f32;
        let (lo, hi) = (whole[i], whole[i + 1]);
        *p = [0, 1, 2, 3].map(|c| lo[c] + (hi[c] - lo[c]) * a);
    }
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
        guide_lengths(&[r(1, 2, 0.4), r(1, 3, 0.3)], 8, &mut lengths).unwrap();
        assert_eq!(lengths, [f32::INFINITY, 0.3, f32::INFINITY]);
        for bad in [
            r(3, 1, 0.5),
            r(0, 0, 0.5),
            r(0, 8, 0.5),
            r(0, 1, f32::NAN),
            r(0, 1, 1.5),
        ] {
            let mut untouched = [7.0f32; 3];
            assert!(guide_lengths(&[bad], 8, &mut untouched).is_err());
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
