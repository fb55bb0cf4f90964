//! The guide cache's unit tests: coding bounds, bit-exact modes, any
//! split into runs, damage refused.

use super::*;
use crate::cache::fixture::{Scene, POINTS};

const GROOM_ID: u32 = 77;

fn scratch(cache: &GuideCache) -> Vec<u32> {
    vec![0; cache.scratch_words()]
}

fn write(groom: &Groom, samples: &[&PosedFrame], mode: Mode) -> Vec<u8> {
    let (g, n) = (groom.guide_roots.len(), groom.points);
    let mut out = vec![0u8; max_encoded_bytes(g, n, samples.len(), mode).unwrap()];
    let written = encode(groom, GROOM_ID, samples, mode, &mut out).unwrap();
    out.truncate(written);
    out
}

/// The scene posed at `t0` and `t1`: the cache of both samples, and a
/// check run on each source frame.
fn two_samples(
    scene: &Scene,
    (t0, t1): (f32, f32),
    mode: Mode,
    mut check: impl FnMut(&[u8], usize, &PosedFrame, &crate::testmesh::TestMesh),
) {
    let (m0, w0) = scene.posed(t0);
    let (m1, w1) = scene.posed(t1);
    scene.with_frame(&m0, &w0, |f0| {
        scene.with_frame(&m1, &w1, |f1| {
            let bytes = write(&scene.groom(), &[f0, f1], mode);
            check(&bytes, 0, f0, &m0);
            check(&bytes, 1, f1, &m1);
        })
    });
}

#[test]
fn quantized_samples_decode_within_the_bound() {
    let scene = Scene::new(600);
    let groom = scene.groom();
    let mut worst = 0.0f32;
    two_samples(
        &scene,
        (0.8, 1.0),
        Mode::Quantized,
        |bytes, s, source, mesh| {
            let cache = GuideCache::parse(bytes).unwrap();
            assert_eq!(cache.info().samples, 2);
            // decoded into a frame of the sample's mesh, posed with other guides
            let (_, other) = scene.posed(0.3);
            scene.with_frame(mesh, &other, |f| {
                cache
                    .decode(&groom, GROOM_ID, s, f, &mut scratch(&cache))
                    .unwrap();
                for g in 0..f.guide_count() {
                    let rest = &groom.guide_points[g * POINTS..(g + 1) * POINTS];
                    let bound = rest_length(rest) / 32768.0;
                    for j in 0..POINTS {
                        let (a, b) = (f.local_point(g, j), source.local_point(g, j));
                        let err = (a - b).abs().max_element();
                        let ulp = b.abs().max_element() * f32::EPSILON;
                        assert!(err <= bound + ulp, "guide {g} point {j}: {err} > {bound}");
                        worst = worst.max(err / bound);
                        assert!(f.world_point(g, j).is_finite());
                    }
                }
            });
        },
    );
    // the bound is reached, not far above what rounding gives
    assert!(worst > 0.9, "{worst}");
}

#[test]
fn exact_samples_decode_bit_for_bit() {
    let scene = Scene::new(300);
    let groom = scene.groom();
    two_samples(&scene, (0.5, 1.0), Mode::Exact, |bytes, s, source, mesh| {
        let cache = GuideCache::parse(bytes).unwrap();
        let (_, other) = scene.posed(0.1);
        scene.with_frame(mesh, &other, |f| {
            cache
                .decode(&groom, GROOM_ID, s, f, &mut scratch(&cache))
                .unwrap();
            for g in 0..f.guide_count() {
                for j in 0..POINTS {
                    assert_eq!(f.world_point(g, j), source.world_point(g, j));
                    assert_eq!(f.local_point(g, j), source.local_point(g, j));
                }
            }
        });
    });
}

#[test]
fn any_split_into_runs_decodes_the_same_bits() {
    let scene = Scene::new(700);
    let groom = scene.groom();
    two_samples(&scene, (0.4, 0.7), Mode::Quantized, |bytes, s, _, mesh| {
        let cache = GuideCache::parse(bytes).unwrap();
        let (_, other) = scene.posed(0.1);
        let whole = scene.with_frame(mesh, &other, |f| {
            cache
                .decode(&groom, GROOM_ID, s, f, &mut scratch(&cache))
                .unwrap();
            (0..f.guide_count() * POINTS)
                .map(|k| {
                    (
                        f.local_point(k / POINTS, k % POINTS),
                        f.world_point(k / POINTS, k % POINTS),
                    )
                })
                .collect::<Vec<_>>()
        });
        scene.with_frame(mesh, &other, |f| {
            cache.check(&groom, GROOM_ID, s, f).unwrap();
            let mut words = scratch(&cache);
            let per = cache.words_per_guide();
            // block by block, then posed in runs of 7 guides
            for b in 0..cache.blocks() {
                let end = ((b + 1) * BLOCK).min(cache.info().guides);
                let part = &mut words[b * BLOCK * per..end * per];
                cache.unpack(&groom, s, b..b + 1, part).unwrap();
            }
            let decoding = cache.decoding(&groom, f);
            let floats = decoding.filler.floats_per_guide();
            for (r, run) in decoding.data.chunks_mut(7 * floats).enumerate() {
                let guides = run.len() / floats;
                let mine = &words[7 * r * per..(7 * r + guides) * per];
                decoding.filler.fill(7 * r, mine, run).unwrap();
            }
            decoding.finish();
            for (k, &(l, w)) in whole.iter().enumerate() {
                let (g, j) = (k / POINTS, k % POINTS);
                assert_eq!((f.local_point(g, j), f.world_point(g, j)), (l, w));
            }
        });
    });
}

/// Writes a valid CRC into `bytes`.
fn seal(bytes: &mut [u8]) {
    let crc_at = container::header_bytes(FIELDS) - 8;
    let mut h = crc32fast::Hasher::new();
    h.update(&bytes[..crc_at]);
    h.update(&bytes[crc_at + 8..]);
    let crc = h.finalize().to_le_bytes();
    bytes[crc_at..crc_at + 4].copy_from_slice(&crc);
}

#[test]
fn a_guide_at_its_neutral_pose_costs_four_bytes() {
    let scene = Scene::new(300);
    let groom = scene.groom();
    scene.with_frame(&scene.rest, &scene.guide_world, |f| {
        let mut bytes = write(&groom, &[f], Mode::Quantized);
        let g = f.guide_count();
        let table = 4 * (g.div_ceil(BLOCK) + 1);
        assert_eq!(bytes.len(), container::header_bytes(FIELDS) + table + 4 * g);
        // it predicts from no neighbour, so as version 1 it reads the same
        bytes[8..12].copy_from_slice(&1u32.to_le_bytes());
        seal(&mut bytes);
        let cache = GuideCache::parse(&bytes).unwrap();
        let (_, other) = scene.posed(0.5);
        scene.with_frame(&scene.rest, &other, |d| {
            cache
                .decode(&groom, GROOM_ID, 0, d, &mut scratch(&cache))
                .unwrap();
            assert_eq!(d.local_point(9, 4), f.local_point(9, 4));
        });
        bytes[8..12].copy_from_slice(&3u32.to_le_bytes());
        seal(&mut bytes);
        assert!(matches!(
            GuideCache::parse(&bytes),
            Err(Error::VersionMismatch { found: 3, .. })
        ));
    });
}

#[test]
fn neighbouring_guides_code_from_each_other() {
    let scene = Scene::new(300);
    let groom = scene.groom();
    let (mesh, world) = scene.posed(0.8);
    scene.with_frame(&mesh, &world, |f| {
        let n = groom.points;
        let (mut alone, mut chained, mut from_neighbour) = (0, 0, 0);
        let mut before: Option<Coded> = None;
        for g in 0..f.guide_count().min(BLOCK) {
            let rest = &groom.guide_points[g * n..(g + 1) * n];
            let coded = code(f, g, rest, before.as_ref());
            alone += code(f, g, rest, None).bytes;
            chained += coded.bytes;
            from_neighbour += coded
                .ks
                .iter()
                .filter(|&&k| k != ZERO && k & NEIGHBOUR != 0)
                .count();
            before = Some(coded);
        }
        assert!(
            from_neighbour > 0 && chained < alone,
            "{chained} vs {alone}"
        );
    });
}

#[test]
fn a_version_1_label_on_neighbour_coding_is_corrupt() {
    let scene = Scene::new(300);
    let groom = scene.groom();
    let (mesh, world) = scene.posed(0.8);
    scene.with_frame(&mesh, &world, |f| {
        let mut bytes = write(&groom, &[f], Mode::Quantized);
        bytes[8..12].copy_from_slice(&1u32.to_le_bytes());
        seal(&mut bytes);
        // the framing is version 1's; the coding is not
        let cache = GuideCache::parse(&bytes).unwrap();
        assert!(matches!(
            cache.decode(&groom, GROOM_ID, 0, f, &mut scratch(&cache)),
            Err(Error::Corrupt { .. })
        ));
    });
}

#[test]
fn sizes_are_asked_for_counts_a_cache_can_hold() {
    let size = |g, n, s| max_encoded_bytes(g, n, s, Mode::Quantized);
    assert!(size(10, 8, 1).is_ok() && size(1, 2, 255).is_ok() && size(1, 64, 1).is_ok());
    for (g, n, s) in [(0, 8, 1), (10, 1, 1), (10, 65, 1), (10, 8, 0), (10, 8, 256)] {
        assert!(
            matches!(size(g, n, s), Err(Error::InvalidArgument(_))),
            "{g} {n} {s}"
        );
    }
    // past 4 GB, and past usize
    for g in [1 << 30, usize::MAX / 2, usize::MAX] {
        assert!(
            matches!(size(g, 8, 2), Err(Error::InvalidArgument(_))),
            "{g}"
        );
    }
}

#[test]
fn wild_guides_fit_the_largest_size() {
    // offsets zig-zagging by thousands of guide lengths cost more as
    // Rice codes than as floats: such guides are stored raw
    let scene = Scene::new(300);
    let groom = scene.groom();
    let mut world = scene.guide_world.clone();
    for (k, p) in world.iter_mut().enumerate() {
        p[0] += if k % 2 == 0 { 4000.0 } else { -4000.0 } * (k % POINTS) as f32;
    }
    scene.with_frame(&scene.rest, &world, |f| {
        let bytes = write(&groom, &[f], Mode::Quantized);
        let cache = GuideCache::parse(&bytes).unwrap();
        let (_, other) = scene.posed(0.5);
        scene.with_frame(&scene.rest, &other, |d| {
            cache
                .decode(&groom, GROOM_ID, 0, d, &mut scratch(&cache))
                .unwrap();
            assert_eq!(d.local_point(7, 5), f.local_point(7, 5));
        });
    });
}

#[test]
fn a_bad_guide_set_is_refused() {
    let scene = Scene::new(300);
    scene.with_frame(&scene.rest, &scene.guide_world, |f| {
        let bytes = write(&scene.groom(), &[f], Mode::Quantized);
        let cache = GuideCache::parse(&bytes).unwrap();
        let mut points = scene.guide_local.clone();
        points[40][2] = f32::NAN;
        let mut groom = scene.groom();
        groom.guide_points = &points;
        assert!(cache
            .decode(&groom, GROOM_ID, 0, f, &mut scratch(&cache))
            .is_err());
        groom.guide_points = &scene.guide_local[1..];
        assert!(matches!(
            cache.decode(&groom, GROOM_ID, 0, f, &mut scratch(&cache)),
            Err(Error::InvalidArgument(_))
        ));
    });
}

#[test]
fn damaged_caches_are_refused_and_the_frame_kept() {
    let scene = Scene::new(300);
    let groom = scene.groom();
    two_samples(
        &scene,
        (0.2, 0.9),
        Mode::Quantized,
        |bytes, s, source, mesh| {
            if s == 1 {
                return;
            }
            let (_, other) = scene.posed(0.5);
            scene.with_frame(mesh, &other, |f| {
                let before: Vec<_> = (0..f.guide_count() * POINTS)
                    .map(|k| f.world_point(k / POINTS, k % POINTS))
                    .collect();
                let kept = |f: &PosedFrame| {
                    (0..f.guide_count() * POINTS)
                        .all(|k| f.world_point(k / POINTS, k % POINTS) == before[k])
                };
                let mut decode = |b: &[u8]| {
                    GuideCache::parse(b)
                        .and_then(|c| c.decode(&groom, GROOM_ID, 0, f, &mut scratch(&c)))
                };
                for len in (0..bytes.len()).step_by(7) {
                    assert!(decode(&bytes[..len]).is_err(), "truncated to {len}");
                }
                for at in (0..bytes.len()).step_by(13) {
                    let mut bad = bytes.to_vec();
                    bad[at] ^= 0x04;
                    assert!(decode(&bad).is_err(), "bit flipped at {at}");
                }
                // a width past 40 bits, a bad tag, and a block's first
                // guide coded from a guide before it, sealed with a
                // valid CRC
                let stream = container::header_bytes(FIELDS) + 4 * (2 * 2 + 1);
                for (at, value) in [(stream + 1, 41u8), (stream, 9), (stream + 1, 0x85)] {
                    let mut bad = bytes.to_vec();
                    bad[at] = value;
                    seal(&mut bad);
                    assert!(matches!(decode(&bad), Err(Error::Corrupt { .. })));
                }
                let cache = GuideCache::parse(bytes).unwrap();
                assert!(matches!(
                    cache.decode(&groom, GROOM_ID + 1, 0, f, &mut scratch(&cache)),
                    Err(Error::InvalidArgument(_))
                ));
                assert!(matches!(
                    cache.decode(&groom, GROOM_ID, 2, f, &mut scratch(&cache)),
                    Err(Error::InvalidArgument(_))
                ));
                let short = &mut scratch(&cache)[1..];
                assert!(matches!(
                    cache.decode(&groom, GROOM_ID, 0, f, short),
                    Err(Error::InvalidArgument(_))
                ));
                assert!(kept(f));
                cache
                    .decode(&groom, GROOM_ID, 0, f, &mut scratch(&cache))
                    .unwrap();
                assert!(!kept(f));
                let err = (f.world_point(5, 3) - source.world_point(5, 3)).length();
                assert!(err < 1e-4, "{err}");
            });
        },
    );
}
