//! The strand kernel: one render strand from its guides, shaped by its
//! groom values (paper 2.2 and 3). Pure per strand: expansion, settling
//! (and later dynamics and trimming) all call it, so a strand is the same
//! bits whichever stage draws it.

use crate::collide::lift::lift;
use crate::interp::bind::{StrandBinding, NO_GUIDE};
use crate::interp::groom::StrandGroom;
use crate::interp::posed::PosedFrame;
use crate::sqrt;
use crate::surface::frame::Frame;
use glam::Vec3;

pub use super::params::{
    lod_width_scale, EndPoints, ExpandParams, MAX_STRAND_POINTS, MAX_WIDTH_SCALE,
};

/// Per-strand working lanes, reused across the strands of one call (zeroing
/// fresh arrays per strand would cost more than the arithmetic).
pub(crate) struct Lanes {
    /// Parameter of each point along the strand, j / (n - 1).
    t: [f32; MAX_STRAND_POINTS],
    local: [f32; 3 * MAX_STRAND_POINTS],
    /// The kink wave without phase for `wave_frequency` (bits; NaN when
    /// none yet): neighbouring strands share a frequency, so it is reused.
    wave: [[f32; MAX_STRAND_POINTS]; 2],
    wave_frequency: u32,
}

impl Lanes {
    pub(crate) fn new(n: usize) -> Self {
        let mut t = [0.0f32; MAX_STRAND_POINTS];
        let step = 1.0 / (n - 1) as f32;
        for (j, tj) in t[..n].iter_mut().enumerate() {
            *tj = j as f32 * step;
        }
        Lanes {
            t,
            local: [0.0; 3 * MAX_STRAND_POINTS],
            wave: [[0.0; MAX_STRAND_POINTS]; 2],
            wave_frequency: f32::NAN.to_bits(),
        }
    }
}

/// Writes one strand into `out`: its `points_per_strand` points, and with
/// pinned ends the first and last again around them
/// ([`ExpandParams::output_points`] in all).
#[inline]
pub(crate) fn strand(
    frame: &Frame,
    bind: &StrandBinding,
    groom: &StrandGroom,
    guides: &PosedFrame,
    params: &ExpandParams,
    lanes: &mut Lanes,
    out: &mut [[f32; 4]],
) {
    // the common counts get loops of known length (unrolled, vectorized
    // whole); the same operations in the same order, so the same bits
    match params.points_per_strand {
        8 => strand_n::<8>(frame, bind, groom, guides, params, lanes, out),
        16 => strand_n::<16>(frame, bind, groom, guides, params, lanes, out),
        32 => strand_n::<32>(frame, bind, groom, guides, params, lanes, out),
        _ => strand_n::<0>(frame, bind, groom, guides, params, lanes, out),
    }
}

/// [`strand`] for `N` points, or for `params.points_per_strand` when `N` is 0.
#[inline(always)]
pub(crate) fn strand_n<const N: usize>(
    frame: &Frame,
    bind: &StrandBinding,
    groom: &StrandGroom,
    guides: &PosedFrame,
    params: &ExpandParams,
    lanes: &mut Lanes,
    out: &mut [[f32; 4]],
) {
    // checked by ExpandParams::check; the min lets the compiler drop bounds checks
    let n = if N == 0 {
        params.points_per_strand.min(MAX_STRAND_POINTS)
    } else {
        N
    };
    let t = &lanes.t[..n];
    // x lanes, then y, then z, as a prepared guide stores its points: the
    // weighted sum is one flat loop over both
    let local = &mut lanes.local[..3 * n];
    let tip = if bind.count == 0 {
        local[..2 * n].fill(0.0);
        for (z, tj) in local[2 * n..].iter_mut().zip(t) {
            *z = params.orphan_length * tj;
        }
        Vec3::new(0.0, 0.0, local[3 * n - 1])
    } else {
        let guide = |k: usize| &guides.local(bind.guides[k] as usize)[..3 * n];
        weigh_guides::<N>(guide, &bind.weights[..bind.count as usize], local)
    };
    let (ax, rest) = local.split_at_mut(n);
    let (ay, az) = rest.split_at_mut(n);
    let scale = groom.length;
    let length = sqrt::length(tip) * scale;
    let bend = groom.bend * length;
    let mut shape = [scale, bend];
    if groom.lift != [0.0; 2] {
        // the lift turns the scaled, bent strand, so it is shaped first
        for j in 0..n {
            ax[j] = ax[j] * scale + bend * t[j] * t[j];
            ay[j] *= scale;
            az[j] *= scale;
        }
        lift(groom.lift, ax, ay, az);
        shape = [1.0, 0.0];
    }
    let clump = if bind.clump == NO_GUIDE {
        0.0
    } else {
        groom.clump
    };
    let kink = groom.kink_amplitude * length;
    let w = params.width_scale;
    let (r0, dr) = (
        groom.root_radius * w,
        (groom.tip_radius - groom.root_radius) * w,
    );
    let look = Look {
        shape,
        clump,
        kink,
        phase: groom.kink_phase,
        radius: [r0, dr],
    };
    let pinned = params.end_points == EndPoints::Pinned;
    let shift = pinned as usize;
    let local = [&*ax, &*ay, &*az];
    let dst = &mut out[shift..shift + n];
    if clump == 0.0 && kink == 0.0 {
        place::<false>(frame, t, local, &NO_CLUMP, &lanes.wave, &look, dst);
    } else {
        if kink != 0.0 && lanes.wave_frequency != groom.kink_frequency.to_bits() {
            let [ws, wc] = &mut lanes.wave;
            kink_wave(groom.kink_frequency, n, &mut ws[..n], &mut wc[..n]);
            lanes.wave_frequency = groom.kink_frequency.to_bits();
        }
        let centre = match bind.clump {
            NO_GUIDE => &NO_CLUMP[..3 * n],
            g => &guides.world(g as usize)[..3 * n],
        };
        place::<true>(frame, t, local, centre, &lanes.wave, &look, dst);
    }
    // the output was stored point by point (16 bytes), so these loads
    // forward from the stores
    if pinned {
        out[0] = out[1];
        out[n + 1] = out[n];
    }
}

/// `out = sum over k of guide(k) * weights[k]` (at least one weight),
/// summed in guide order, so to the same bits on either path; returns the
/// sum's last point (the tip).
///
/// For the point counts of known length the sums stay in registers over
/// the guides (8, 16 or 32 points take 3, 6 or 12 AVX registers) and give
/// the tip from there: a pass per guide over `out` stored and reloaded
/// every lane per guide, which cost more than the arithmetic.
#[inline(always)]
fn weigh_guides<'g, const N: usize>(
    guide: impl Fn(usize) -> &'g [f32],
    weights: &[f32],
    out: &mut [f32],
) -> Vec3 {
    match N {
        8 => weigh_lanes::<3>(guide, weights, out),
        16 => weigh_lanes::<6>(guide, weights, out),
        32 => weigh_lanes::<12>(guide, weights, out),
        _ => {
            let w = weights[0];
            for (a, g) in out.iter_mut().zip(guide(0)) {
                *a = g * w;
            }
            for (k, &w) in weights.iter().enumerate().skip(1) {
                for (a, g) in out.iter_mut().zip(guide(k)) {
                    *a += g * w;
                }
            }
            let n = out.len() / 3;
            Vec3::new(out[n - 1], out[2 * n - 1], out[3 * n - 1])
        }
    }
}

/// Floats per [`weigh_lanes`] accumulator: one AVX register.
const LANE: usize = 8;

/// [`weigh_guides`] for `C` whole lanes: each accumulator a fixed-size
/// array, so that each becomes one register.
#[inline(always)]
fn weigh_lanes<'g, const C: usize>(
    guide: impl Fn(usize) -> &'g [f32],
    weights: &[f32],
    out: &mut [f32],
) -> Vec3 {
    let lane = |g: &'g [f32], c: usize| -> &'g [f32; LANE] {
        g[c * LANE..(c + 1) * LANE].try_into().unwrap()
    };
    let (first, w) = (guide(0), weights[0]);
    let mut acc: [[f32; LANE]; C] = core::array::from_fn(|c| lane(first, c).map(|x| x * w));
    for (k, &w) in weights.iter().enumerate().skip(1) {
        let g = guide(k);
        for (c, a) in acc.iter_mut().enumerate() {
            let g = lane(g, c);
            for l in 0..LANE {
                a[l] += g[l] * w;
            }
        }
    }
    for (o, a) in out.chunks_exact_mut(LANE).zip(&acc) {
        o.copy_from_slice(a);
    }
    // x, y and z take a third of the lanes each
    let last = |third: usize| acc[third * C / 3 - 1][LANE - 1];
    Vec3::new(last(1), last(2), last(3))
}

/// Stand-in clump centre for a strand without one (its pull is 0).
static NO_CLUMP: [f32; 3 * MAX_STRAND_POINTS] = [0.0; 3 * MAX_STRAND_POINTS];

/// One strand's look, from its groom values and its length.
struct Look {
    /// Length scale, and bend offset at the tip (both applied to local points).
    shape: [f32; 2],
    /// Pull toward the clump centre at the tip.
    clump: f32,
    /// Kink amplitude at the tip.
    kink: f32,
    /// Cosine and sine of the kink phase.
    phase: [f32; 2],
    /// Root radius, and tip minus root radius.
    radius: [f32; 2],
}

/// Places the local points `a` in the world through `frame`, pulls them
/// toward the clump centre `c` and adds the kink wave `wave` (when
/// `CLUMP_KINK`), and writes the points with their radii to `out`.
///
/// One pass per point with everything in registers: separate passes
/// stored and reloaded every lane between steps. A zero pull or kink
/// changes nothing, so one loop serves a strand with either.
#[inline(always)]
fn place<const CLUMP_KINK: bool>(
    frame: &Frame,
    t: &[f32],
    a: [&[f32]; 3],
    c: &[f32],
    wave: &[[f32; MAX_STRAND_POINTS]; 2],
    look: &Look,
    out: &mut [[f32; 4]],
) {
    let n = out.len();
    let (t, [ax, ay, az]) = (&t[..n], a.map(|a| &a[..n]));
    let (cx, cy, cz) = (&c[..n], &c[n..2 * n], &c[2 * n..3 * n]);
    let (ws, wc) = (&wave[0][..n], &wave[1][..n]);
    let (o, tt, b, nn) = (frame.origin, frame.t, frame.b, frame.n);
    let [scale, bend] = look.shape;
    let [cp, sp] = look.phase;
    let [r0, dr] = look.radius;
    for j in 0..n {
        let lx = ax[j] * scale + bend * t[j] * t[j];
        let (ly, lz) = (ay[j] * scale, az[j] * scale);
        let mut x = o.x + tt.x * lx + b.x * ly + nn.x * lz;
        let mut y = o.y + tt.y * lx + b.y * ly + nn.y * lz;
        let mut z = o.z + tt.z * lx + b.z * ly + nn.z * lz;
        if CLUMP_KINK {
            let pull = look.clump * t[j];
            x += (cx[j] - x) * pull;
            y += (cy[j] - y) * pull;
            z += (cz[j] - z) * pull;
            // sin and cos of (phase + j delta)
            let (ks, kc) = (sp * wc[j] + cp * ws[j], cp * wc[j] - sp * ws[j]);
            let k = look.kink * t[j];
            x += (tt.x * ks + b.x * kc) * k;
            y += (tt.y * ks + b.y * kc) * k;
            z += (tt.z * ks + b.z * kc) * k;
        }
        out[j] = [x, y, z, r0 + dr * t[j]];
    }
}

/// sin and cos of `j * delta` for the `n` points of a kink wave of
/// `frequency` waves per strand, by rotation recurrences: four interleaved
/// chains, so the serial dependency is a quarter as long as one chain's.
/// A pure function of `frequency` and `n`.
fn kink_wave(frequency: f32, n: usize, sin: &mut [f32], cos: &mut [f32]) {
    const CHAINS: usize = 4;
    let delta = core::f32::consts::TAU * frequency / (n - 1) as f32;
    let (s1, c1) = libm::sincosf(delta);
    // the rotation by 4 delta by two double-angle steps, not another sincos
    let (s2, c2) = (2.0 * s1 * c1, c1 * c1 - s1 * s1);
    let (s4, c4) = (2.0 * s2 * c2, c2 * c2 - s2 * s2);
    let (mut s, mut c) = ([0.0f32; CHAINS], [1.0f32; CHAINS]);
    for i in 1..CHAINS {
        (s[i], c[i]) = (s[i - 1] * c1 + c[i - 1] * s1, c[i - 1] * c1 - s[i - 1] * s1);
    }
    for (sj, cj) in sin.chunks_mut(CHAINS).zip(cos.chunks_mut(CHAINS)) {
        sj.copy_from_slice(&s[..sj.len()]);
        cj.copy_from_slice(&c[..cj.len()]);
        for i in 0..CHAINS {
            (s[i], c[i]) = (s[i] * c4 + c[i] * s4, c[i] * c4 - s[i] * s4);
        }
    }
}
