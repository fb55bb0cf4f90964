//! The per-frame guide cache on the animated creature's simulated shot
//! (walk, turn, jump, sway, a 100-unit teleport): every frame's shutter
//! samples decode from that frame's file and the groom alone, within the
//! stated bound of 2^-15 of the guide length per root-frame coordinate,
//! and far smaller than plain 16-bit guides.

use pelage_core::cache::groom_file::{self, Groom};
use pelage_core::cache::guide_cache::{self, GuideCache, Mode};
use pelage_core::guides::{CvLayout, Guides};
use pelage_core::interp::posed::PosedFrame;
use pelage_core::interp::strands::Strands;
use pelage_core::{Arena, ArenaLayout, Strided};
use pelage_tests::animated::simulate_shot;
use pelage_tests::creature::CreatureMesh;
use pelage_tests::measure::mesh_view;

const GUIDES: u32 = 2_000;
const POINTS: usize = 16;

/// Runs `f` on a frame of `mesh` posed with `points`.
fn with_frame<T>(
    mesh: &CreatureMesh,
    roots: &[pelage_core::Root],
    points: &[[f32; 3]],
    f: impl FnOnce(&mut PosedFrame) -> T,
) -> T {
    let mut layout = ArenaLayout::new();
    PosedFrame::layout(&mut layout, mesh.positions.len(), roots.len(), POINTS);
    let mut buf = vec![0u8; layout.bytes()];
    let guides = Guides {
        roots,
        points: Strided::from_slice(points),
        layout: CvLayout::Fixed(POINTS),
    };
    let mut frame =
        PosedFrame::with_guides(mesh_view(mesh), &guides, POINTS, &mut Arena::new(&mut buf))
            .unwrap();
    f(&mut frame)
}

#[test]
fn every_frame_decodes_from_its_own_file_within_the_bound() {
    let shot = simulate_shot(GUIDES, POINTS);
    let roots = &shot.roots;
    let rest_local = shot.rest_local();
    let groom = Groom::of_guides(roots, &rest_local, POINTS);
    let mut groom_bytes = vec![0u8; groom.encoded_bytes().unwrap()];
    groom_file::encode(&groom, &mut groom_bytes).unwrap();
    let id = groom_file::counts(&groom_bytes).unwrap().id;
    let lengths: Vec<f32> = rest_local
        .chunks(POINTS)
        .map(|g| {
            g.windows(2)
                .map(|w| glam::Vec3::from(w[1]).distance(glam::Vec3::from(w[0])))
                .sum()
        })
        .collect();
    let frames = shot.meshes.len();
    let (mut total, mut worst) = (0usize, 0.0f32);
    // shutter open at the frame, close at the next
    for f in 0..frames - 1 {
        let samples = [f, f + 1];
        let bytes = with_frame(&shot.meshes[f], roots, &shot.posed[f], |open| {
            with_frame(&shot.meshes[f + 1], roots, &shot.posed[f + 1], |close| {
                let s = [&*open, &*close];
                let most = guide_cache::max_encoded_bytes(roots.len(), POINTS, 2, Mode::Quantized);
                let mut out = vec![0u8; most.unwrap()];
                let written =
                    guide_cache::encode(&groom, id, &s, Mode::Quantized, &mut out).unwrap();
                out.truncate(written);
                out
            })
        });
        total += bytes.len();
        let cache = GuideCache::parse(&bytes).unwrap();
        for (s, &source) in samples.iter().enumerate() {
            // decoded into a frame of the sample's mesh holding other guides
            let other = &shot.posed[(source + 40) % frames];
            with_frame(&shot.meshes[source], roots, other, |decoded| {
                cache
                    .decode(&groom, id, s, decoded, &mut vec![0; cache.scratch_words()])
                    .unwrap();
                with_frame(&shot.meshes[source], roots, &shot.posed[source], |truth| {
                    for (g, length) in lengths.iter().enumerate() {
                        let bound = length / 32768.0;
                        for j in 0..POINTS {
                            let (a, b) = (decoded.local_point(g, j), truth.local_point(g, j));
                            let err = (a - b).abs().max_element();
                            let rounding = b.abs().max_element() * f32::EPSILON;
                            assert!(
                                err <= bound + rounding,
                                "frame {source} guide {g} point {j}: {err} > {bound}"
                            );
                            worst = worst.max(err / bound);
                            assert!(decoded.world_point(g, j).is_finite());
                        }
                    }
                });
            });
        }
    }
    let per_point = total as f64 / ((frames - 1) * 2 * roots.len() * POINTS) as f64;
    println!(
        "{} frames x 2 samples: {:.2} bytes per guide point (plain 16-bit: 6), worst error {:.3} of the bound",
        frames - 1,
        per_point,
        worst
    );
    // 3.15 when measured; plain 16-bit guides take 6
    assert!(per_point < 3.5, "{per_point} bytes per point");
}

/// Patches of the creature's fur on its simulated shot: every expanded
/// point, radius included, inside its patch's box, on every frame sampled
/// (the teleport among them), with the boxes computed from the guides and
/// groom records alone.
#[test]
fn no_expanded_point_leaves_its_patch_box() {
    use pelage_core::interp::expand::expand;
    use pelage_core::interp::groom::{GroomMaps, StrandGroom};
    use pelage_core::interp::patch::{self, Patch};
    use pelage_core::interp::strand::{EndPoints, ExpandParams};
    use pelage_core::ScalarMap;
    use pelage_tests::animated::TELEPORT_FRAME;
    use pelage_tests::measure::{bind_vec, stamp_roots};

    const HAIRS: u32 = 60_000;
    const PATCH: usize = 500;
    let shot = simulate_shot(GUIDES, POINTS);
    let mesh = mesh_view(&shot.rest);
    let stamped = stamp_roots(mesh, HAIRS, 2);
    // patches: Morton runs, ranked inside; strands reordered by them
    let (mut keys, mut order) = (vec![0u64; stamped.len()], vec![0u32; stamped.len()]);
    let mut patches = vec![Patch::default(); patch::patch_count(stamped.len(), PATCH)];
    patch::plan(&mesh, &stamped, PATCH, &mut keys, &mut order, &mut patches).unwrap();
    let hairs: Vec<_> = order.iter().map(|&i| stamped[i as usize]).collect();
    let bindings = bind_vec(&mesh, &shot.roots, &shot.rest_points, POINTS, &hairs);
    let mut grooms = vec![StrandGroom::default(); hairs.len()];
    let maps = GroomMaps {
        kink_amplitude: ScalarMap::Constant(0.05),
        clump: ScalarMap::Constant(0.3),
        bend: ScalarMap::Constant(0.1),
        ..GroomMaps::default()
    };
    maps.evaluate(&mesh, &hairs, 0, &mut grooms).unwrap();
    let strands = Strands {
        roots: &hairs,
        bindings: &bindings,
        grooms: &grooms,
    };
    let params = ExpandParams {
        points_per_strand: POINTS,
        end_points: EndPoints::Pinned,
        orphan_length: 0.04,
        width_scale: 1.0,
    };
    let per = params.output_points();
    let mut out = vec![[0.0f32; 4]; hairs.len() * per];
    let (mut checked, mut volume_ratio) = (0usize, vec![]);
    for f in (0..shot.meshes.len())
        .step_by(8)
        .chain([TELEPORT_FRAME as usize])
    {
        with_frame(&shot.meshes[f], &shot.roots, &shot.posed[f], |frame| {
            let mut reach = vec![0.0f32; frame.guide_count()];
            patch::guide_reach(frame, &mut reach);
            expand(
                frame,
                &strands,
                &params,
                bytemuck::cast_slice_mut(&mut out),
                16,
            )
            .unwrap();
            for p in &patches {
                let b = patch::patch_box(frame, &reach, &strands, &params, *p);
                let (mut lo, mut hi) = (
                    glam::Vec3::splat(f32::INFINITY),
                    glam::Vec3::splat(f32::NEG_INFINITY),
                );
                let range = p.first as usize * per..(p.first + p.count) as usize * per;
                for q in &out[range] {
                    let (c, r) = (glam::Vec3::new(q[0], q[1], q[2]), glam::Vec3::splat(q[3]));
                    assert!(
                        b.contains(c - r) && b.contains(c + r),
                        "frame {f}: a point of patch {p:?} outside its box"
                    );
                    (lo, hi) = (lo.min(c - r), hi.max(c + r));
                    checked += 1;
                }
                volume_ratio.push(((b.hi - b.lo) / (hi - lo)).max_element());
            }
        });
    }
    volume_ratio.sort_by(f32::total_cmp);
    println!(
        "{checked} points inside their patch boxes; box extent over the points' extent, median {:.2}, worst {:.2}",
        volume_ratio[volume_ratio.len() / 2],
        volume_ratio[volume_ratio.len() - 1]
    );
}
