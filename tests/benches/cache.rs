//! The per-frame guide cache at the paper's gorilla scale: 13,030 guides x
//! 16 points simulated over the animated creature's 96-frame shot, each
//! frame coded (quantized, one and two shutter samples; exact) and decoded
//! into a posed frame. Reports bytes per frame against the same frame as
//! dense float32 curves (979,526 hairs x 18 points x float4, 282 MB; the
//! paper: 47x) and against plain 16-bit guides, encode and decode times
//! (medians over the shot), decode speed (in world points, and in all the
//! floats decode writes: root-frame and world points), and a
//! floor measured in the same run: posing the same frame from float32
//! guides in memory (`PosedFrame::pose`, what decoding replaces).

use pelage_core::cache::groom_file::{self, Groom};
use pelage_core::cache::guide_cache::{self, GuideCache, Mode};
use pelage_core::guides::{CvLayout, Guides};
use pelage_core::interp::posed::PosedFrame;
use pelage_core::{Arena, ArenaLayout, Strided};
use pelage_tests::animated::simulate_shot;
use std::time::Instant;

const GUIDES: u32 = 13_030;
const POINTS: usize = 16;
const DENSE_BYTES: f64 = 979_526.0 * 18.0 * 16.0;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let shot = simulate_shot(GUIDES, POINTS);
    let roots = &shot.roots;
    let g = roots.len();
    let layout = |mesh: &pelage_tests::creature::CreatureMesh| {
        let mut l = ArenaLayout::new();
        PosedFrame::layout(&mut l, mesh.positions.len(), g, POINTS);
        l.bytes()
    };
    fn guides<'a>(roots: &'a [pelage_core::Root], points: &'a [[f32; 3]]) -> Guides<'a> {
        Guides {
            roots,
            points: Strided::from_slice(points),
            layout: CvLayout::Fixed(POINTS),
        }
    }
    let rest_local = shot.rest_local();
    let groom = Groom::of_guides(roots, &rest_local, POINTS);
    let mut groom_bytes = vec![0u8; groom.encoded_bytes().unwrap()];
    groom_file::encode(&groom, &mut groom_bytes).unwrap();
    let id = groom_file::counts(&groom_bytes).unwrap().id;

    let frames = shot.meshes.len();
    let mut bufs: Vec<Vec<u8>> = shot.meshes.iter().map(|m| vec![0u8; layout(m)]).collect();
    let posed: Vec<PosedFrame> = bufs
        .iter_mut()
        .enumerate()
        .map(|(f, buf)| {
            let gd = guides(roots, &shot.posed[f]);
            PosedFrame::with_guides(
                pelage_tests::measure::mesh_view(&shot.meshes[f]),
                &gd,
                POINTS,
                &mut Arena::new(buf),
            )
            .unwrap()
        })
        .collect();
    let mut target_buf = vec![0u8; shot.meshes.iter().map(layout).max().unwrap()];
    let mut scratch = vec![0u32; g * (1 + 3 * POINTS)];
    println!(
        "creature: {g} guides x {POINTS} points, {frames} frames; dense float32 frame: {:.1} MB; plain 16-bit guides: {:.2} MB",
        DENSE_BYTES / 1e6,
        (g * POINTS * 6) as f64 / 1e6
    );
    println!(
        "{:>24} | {:>10} {:>10} | {:>8} {:>8} | {:>9} {:>9} {:>9} {:>9} | {:>5} {:>5} {:>5} {:>5}",
        "per frame (medians)",
        "KB",
        "max KB",
        "x dense",
        "x 16-bit",
        "encode ms",
        "decode 1T",
        "decode 2T",
        "floor 1T",
        "GB/s",
        "2T",
        "all",
        "2T"
    );
    for (name, samples, mode) in [
        ("quantized, 1 sample", 1usize, Mode::Quantized),
        ("quantized, 2 samples", 2, Mode::Quantized),
        ("exact float32, 1 sample", 1, Mode::Exact),
    ] {
        let (mut sizes, mut enc, mut dec, mut floor) = (vec![], vec![], vec![], vec![]);
        let mut dec2 = vec![];
        for f in 0..frames - samples + 1 {
            let s: Vec<&PosedFrame> = (0..samples).map(|k| &posed[f + k]).collect();
            let mut out =
                vec![0u8; guide_cache::max_encoded_bytes(g, POINTS, samples, mode).unwrap()];
            let t = Instant::now();
            let n = guide_cache::encode(&groom, id, &s, mode, &mut out).unwrap();
            enc.push(t.elapsed().as_secs_f64());
            out.truncate(n);
            sizes.push(n as f64 / samples as f64);
            let view = pelage_tests::measure::mesh_view(&shot.meshes[f]);
            let mut target =
                PosedFrame::new(view, g, POINTS, &mut Arena::new(&mut target_buf)).unwrap();
            let t = Instant::now();
            let cache = GuideCache::parse(&out).unwrap();
            cache
                .decode(&groom, id, 0, &mut target, &mut scratch)
                .unwrap();
            dec.push(t.elapsed().as_secs_f64());
            let one: Vec<f32> = (0..g * POINTS)
                .map(|k| target.world_point(k / POINTS, k % POINTS).x)
                .collect();
            let t = Instant::now();
            decode_on_two_threads(&cache, &groom, id, &mut target, &mut scratch);
            dec2.push(t.elapsed().as_secs_f64());
            assert!((0..g * POINTS).all(|k| target.world_point(k / POINTS, k % POINTS).x == one[k]));
            let gd = guides(roots, &shot.posed[f]);
            let t = Instant::now();
            target.pose(&gd).unwrap();
            floor.push(t.elapsed().as_secs_f64());
        }
        let size = median(sizes.clone());
        let max = sizes.iter().cloned().fold(0.0, f64::max);
        let (d, d2) = (median(dec), median(dec2));
        println!(
            "{name:>24} | {:>10.1} {:>10.1} | {:>7.0}x {:>7.2}x | {:>9.2} {:>9.2} {:>9.2} {:>9.2} | {:>5.2} {:>5.2} {:>5.2} {:>5.2}",
            size / 1e3,
            max / 1e3,
            DENSE_BYTES / size,
            (g * POINTS * 6) as f64 / size,
            median(enc) * 1e3,
            d * 1e3,
            d2 * 1e3,
            median(floor) * 1e3,
            (g * POINTS * 12) as f64 / d / 1e9,
            (g * POINTS * 12) as f64 / d2 / 1e9,
            (g * POINTS * 24) as f64 / d / 1e9,
            (g * POINTS * 24) as f64 / d2 / 1e9
        );
    }
    println!(
        "(KB per shutter sample; decode: one sample into a posed frame on 1 and 2 threads (the same bits); GB/s: of world points, and of all the floats decode writes (root-frame and world points))"
    );
    println!(
        "groom file of the guides alone: {:.2} MB",
        groom_bytes.len() as f64 / 1e6
    );
}

/// [`GuideCache::decode`] split over two threads by runs of blocks, as the
/// C API does.
fn decode_on_two_threads(
    cache: &GuideCache,
    groom: &Groom,
    id: u32,
    frame: &mut PosedFrame,
    scratch: &mut [u32],
) {
    use pelage_core::cache::guide_cache::BLOCK;
    cache.check(groom, id, 0, frame).unwrap();
    let (blocks, words) = (cache.blocks(), cache.words_per_guide());
    let half = blocks / 2;
    let unpacked = &mut scratch[..cache.scratch_words()];
    let (first, second) = unpacked.split_at_mut(half * BLOCK * words);
    std::thread::scope(|s| {
        let a = s.spawn(|| cache.unpack(groom, 0, 0..half, first));
        cache.unpack(groom, 0, half..blocks, second).unwrap();
        a.join().unwrap().unwrap();
    });
    let decoding = cache.decoding(groom, frame);
    let filler = decoding.filler;
    let guides = cache.info().guides;
    let (first, second) = decoding
        .data
        .split_at_mut(guides / 2 * filler.floats_per_guide());
    let (words_a, words_b) = unpacked.split_at(guides / 2 * words);
    std::thread::scope(|s| {
        let a = s.spawn(|| filler.fill(0, words_a, first));
        filler.fill(guides / 2, words_b, second).unwrap();
        a.join().unwrap().unwrap();
    });
    decoding.finish();
}
