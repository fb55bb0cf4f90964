//! Trimming at a shirt over a shot (paper 3.3), end to end through the C
//! API: the animated creature wears a shirt (its torso, 0.03 off the
//! skin, deforming with it); each frame's simulated guides are trimmed
//! where they meet the shirt or the capsules, the records go through their
//! file, the shot pass keeps each hair's shortest length, and the render
//! hairs cut by it never change length between frames and cross the shirt
//! far less than uncut; cut by the exact shot pass on their own curves,
//! no hair crosses it on any frame.

use glam::Vec3;
use pelage::*;
use pelage_core::surface::body::Body;
use pelage_core::Arena;
use pelage_tests::animated::{capsules, colliders, pose, segment_distance};
use pelage_tests::creature::{default_creature, CreatureMesh};
use pelage_tests::measure::{
    curves_desc, frame, groomed, guides_desc, mesh_desc, mesh_view, on_threads, strands_desc,
};
use std::collections::HashMap;
use std::ptr::null_mut;

const JOINTS: usize = 12;
const GUIDES: u32 = 1_500;
const LENGTH: f32 = 0.08;
const HAIRS: u32 = 30_000;
const FRAMES: u32 = 24;
/// The shirt's distance off the skin.
const GAP: f32 = 0.03;

/// The shirt on `body`: its torso band `band` pushed `GAP` out along the
/// normals of the deformed surface (area-weighted, shared by the copies
/// of a vertex along the UV seam, so the shirt has no crack there).
fn shirt(body: &CreatureMesh, band: &[[u32; 3]]) -> CreatureMesh {
    let key = |v: u32| body.positions[v as usize].map(f32::to_bits);
    let mut normals: HashMap<[u32; 3], Vec3> = HashMap::new();
    for t in &body.triangles {
        let [a, b, c] = t.map(|v| Vec3::from(body.positions[v as usize]));
        let n = (b - a).cross(c - a);
        for &v in t {
            *normals.entry(key(v)).or_default() += n;
        }
    }
    CreatureMesh {
        positions: (0..body.positions.len() as u32)
            .map(|v| {
                let n = normals
                    .get(&key(v))
                    .map_or(Vec3::ZERO, |n| n.normalize_or_zero());
                (Vec3::from(body.positions[v as usize]) + n * GAP).to_array()
            })
            .collect(),
        triangles: band.to_vec(),
        ..body.clone()
    }
}

fn ok(s: PelageStatus, what: &str) {
    assert_eq!(s, PelageStatus::Ok, "{what}: {}", last_error());
}

fn last_error() -> String {
    // SAFETY: pelage_last_error returns a NUL-terminated string owned by
    // the library, valid until the next failing call on this thread.
    unsafe { std::ffi::CStr::from_ptr(pelage_last_error()) }
        .to_string_lossy()
        .into_owned()
}

/// A frame's trim records, found on `thread_count` threads.
fn find(
    frame: PelageFrame,
    cloth: &PelageMeshDesc,
    col: &PelageColliders,
    threads: u32,
) -> Vec<PelageTrimRecord> {
    let mut records = vec![PelageTrimRecord::default(); GUIDES as usize];
    let mut count = 0;
    ok(
        pelage_trim_find(
            frame,
            cloth,
            col,
            on_threads(threads),
            records.as_mut_ptr(),
            records.len(),
            &mut count,
        ),
        "pelage_trim_find",
    );
    records.truncate(count);
    records
}

/// `records` through a trim records file and back.
fn round_trip(records: &[PelageTrimRecord], guides: usize) -> Vec<PelageTrimRecord> {
    let mut size = 0;
    ok(pelage_trim_records_size(records.len(), &mut size), "size");
    let mut file = vec![0u8; size];
    let mut written = 0;
    ok(
        pelage_trim_records_write(
            records.as_ptr(),
            records.len(),
            guides,
            JOINTS as u32,
            file.as_mut_ptr().cast(),
            size,
            &mut written,
        ),
        "pelage_trim_records_write",
    );
    let mut back = vec![PelageTrimRecord::default(); records.len()];
    let mut info = PelageTrimRecordsInfo::default();
    ok(
        pelage_trim_records_read(
            file.as_ptr().cast(),
            written,
            back.as_mut_ptr(),
            back.len(),
            &mut info,
        ),
        "pelage_trim_records_read",
    );
    assert_eq!(
        (info.guide_count, info.record_count),
        (guides, records.len())
    );
    back
}

/// Segments of `curves` (`per` points each) that cross `cloth`, counted
/// over the hairs `chosen` selects.
fn crossings(
    cloth: &Body,
    curves: &[[f32; 4]],
    per: usize,
    chosen: impl Fn(usize) -> bool,
) -> usize {
    curves
        .chunks(per)
        .enumerate()
        .filter(|&(i, _)| chosen(i))
        .map(|(_, c)| {
            c.windows(2)
                .filter(|w| cloth.blocks(Vec3::from_slice(&w[0]), Vec3::from_slice(&w[1])))
                .count()
        })
        .sum()
}

#[test]
fn a_shirt_trims_the_fur_the_same_on_every_frame_of_a_shot() {
    let rest = default_creature();
    let fur = groomed(
        &rest,
        (GUIDES, JOINTS, LENGTH),
        HAIRS,
        &pelage_groom_maps_defaults(),
        2,
    );
    let guide_count = fur.guide_roots.len();
    let band: Vec<[u32; 3]> = rest
        .triangles
        .iter()
        .copied()
        .filter(|t| {
            t.iter()
                .all(|&v| (-0.25..0.2).contains(&rest.positions[v as usize][1]))
        })
        .collect();
    assert!(band.len() > 1000, "a torso of {} triangles", band.len());

    let mut groom = null_mut();
    let strands = strands_desc(&fur.strands, &fur.bindings, &fur.grooms);
    ok(pelage_groom_new(&strands, &mut groom), "pelage_groom_new");
    let sim =
        pelage_tests::animated::ShotSim::new(&rest, &fur.guide_roots, &fur.guide_points, JOINTS);
    let n = fur.strands.len();
    let params = PelageExpandParams {
        points_per_strand: JOINTS as u32,
        end_points: PelageEndPoints::Raw as u32,
        run: on_threads(2),
        ..pelage_expand_params_defaults()
    };
    let per = JOINTS;

    // the simulation pass: each frame's guides, and its records through their file
    let mut shot = vec![PELAGE_TRIM_WHOLE; n];
    // the exact shot pass, on the hairs' own curves
    let mut exact = vec![PELAGE_TRIM_WHOLE; n];
    let mut frames = vec![];
    let mut per_frame = vec![];
    for f in 0..FRAMES {
        let body = pose(&rest, f);
        let caps = capsules(&rest, &fur.guide_roots, f);
        let col = colliders(&caps, false);
        let posed = sim.step(&body, &col);
        let handle = frame(
            &mesh_desc(&body),
            &guides_desc(&fur.guide_roots, &posed),
            JOINTS as u32,
            2,
        )
        .unwrap();
        let cloth = shirt(&body, &band);
        let records = find(handle.0, &mesh_desc(&cloth), &col, 2);
        assert_eq!(
            records,
            find(handle.0, &mesh_desc(&cloth), &col, 1),
            "any thread count"
        );
        let records = round_trip(&records, guide_count);
        let mut own = vec![PELAGE_TRIM_WHOLE; n];
        for lengths in [&mut own, &mut shot] {
            ok(
                pelage_trim_shortest(
                    groom,
                    records.as_ptr(),
                    records.len(),
                    guide_count,
                    JOINTS as u32,
                    lengths.as_mut_ptr(),
                    n,
                ),
                "pelage_trim_shortest",
            );
        }
        per_frame.push(own);
        ok(
            pelage_trim_shortest_hairs(
                groom,
                handle.0,
                &mesh_desc(&cloth),
                &col,
                &params,
                exact.as_mut_ptr(),
                n,
            ),
            "pelage_trim_shortest_hairs",
        );
        let mut met = vec![false; guide_count];
        for r in &records {
            met[r.guide as usize] = true;
        }
        frames.push((body, cloth, posed, records.len(), met));
    }
    // a cut made on a frame was not checked against the frames before it:
    // the exact pass goes over the shot again until no length changes
    let mut again = 0;
    loop {
        let before = exact.clone();
        for (f, (body, cloth, posed, _, _)) in (0..FRAMES).zip(&frames) {
            let handle = frame(
                &mesh_desc(body),
                &guides_desc(&fur.guide_roots, posed),
                JOINTS as u32,
                2,
            )
            .unwrap();
            let caps = capsules(&rest, &fur.guide_roots, f);
            ok(
                pelage_trim_shortest_hairs(
                    groom,
                    handle.0,
                    &mesh_desc(cloth),
                    &colliders(&caps, false),
                    &params,
                    exact.as_mut_ptr(),
                    n,
                ),
                "pelage_trim_shortest_hairs",
            );
        }
        again += 1;
        if exact == before {
            break;
        }
        assert!(again < 3, "the exact pass settles in two more passes");
    }
    println!("the exact pass went over the shot {again} more times");

    // a pass its progress callback cancels halfway leaves the lengths as
    // they were; the same pass run through cuts some
    unsafe extern "C" fn halfway(_: *mut std::ffi::c_void, fraction: f64) -> bool {
        fraction < 0.5
    }
    let (body, cloth, posed, _, _) = &frames[0];
    let handle = frame(
        &mesh_desc(body),
        &guides_desc(&fur.guide_roots, posed),
        JOINTS as u32,
        2,
    )
    .unwrap();
    let shapes = capsules(&rest, &fur.guide_roots, 0);
    let caps = colliders(&shapes, false);
    let cancelled = PelageExpandParams {
        run: PelageRun {
            progress: Some(halfway),
            ..params.run
        },
        ..params
    };
    let whole = vec![PELAGE_TRIM_WHOLE; n];
    let mut pass = whole.clone();
    for (p, status) in [
        (&cancelled, PelageStatus::Cancelled),
        (&params, PelageStatus::Ok),
    ] {
        let s = pelage_trim_shortest_hairs(
            groom,
            handle.0,
            &mesh_desc(cloth),
            &caps,
            p,
            pass.as_mut_ptr(),
            n,
        );
        assert_eq!(s, status);
        assert_eq!(pass == whole, status == PelageStatus::Cancelled);
    }

    // the shot pass's file: 2 bytes a hair
    let mut size = 0;
    ok(pelage_trim_lengths_size(n, &mut size), "size");
    let mut file = vec![0u8; size];
    let mut written = 0;
    ok(
        pelage_trim_lengths_write(
            shot.as_ptr(),
            n,
            file.as_mut_ptr().cast(),
            size,
            &mut written,
        ),
        "pelage_trim_lengths_write",
    );
    let mut lengths = vec![0u16; n];
    let mut count = 0;
    ok(
        pelage_trim_lengths_read(
            file.as_ptr().cast(),
            written,
            lengths.as_mut_ptr(),
            n,
            &mut count,
        ),
        "pelage_trim_lengths_read",
    );
    assert_eq!((lengths.as_slice(), count), (shot.as_slice(), n));
    let trimmed: Vec<bool> = lengths.iter().map(|&l| l < PELAGE_TRIM_WHOLE).collect();
    let trimmed_count = trimmed.iter().filter(|&&t| t).count();
    let changes: usize = per_frame
        .windows(2)
        .map(|w| w[0].iter().zip(&w[1]).filter(|(a, b)| a != b).count())
        .sum();
    println!(
        "{n} hairs, {guide_count} guides, {FRAMES} frames: {trimmed_count} hairs trimmed by the shot pass; \
         records per frame {:?}; lengths file {written} bytes ({:.2} bytes a hair)",
        frames.iter().map(|f| f.3).collect::<Vec<_>>(),
        written as f64 / n as f64
    );
    println!(
        "length changes frame to frame: {changes} without the shot pass, 0 with it (one file)"
    );
    assert!(
        trimmed_count > n / 20,
        "the shirt trims a good part of the fur"
    );
    assert!(changes > 0, "the shot moves the cut from frame to frame");

    // the render pass: every frame expanded with the shot's lengths
    let (mut crossed, mut crossed_whole, mut crossed_inside, mut hairs_inside) = (0, 0, 0, 0);
    let mut crossed_exact = 0;
    // each hair the exact pass cut meets the shirt or a capsule within a
    // segment past its cut on some frame: the cut is not much shorter than
    // a frame needs. A few are cut shorter: a cut curve's respread points
    // cut its corners, and where their chords still meet the shirt the
    // cut moves to that meet (`clear_cut`)
    let mut reached = vec![false; n];
    for (f, (body, cloth, posed, _, met)) in (0..FRAMES).zip(&frames) {
        let handle = frame(
            &mesh_desc(body),
            &guides_desc(&fur.guide_roots, posed),
            JOINTS as u32,
            2,
        )
        .unwrap();
        let mut cut = vec![[0.0f32; 4]; n * per];
        ok(
            pelage_groom_expand_edited(
                groom,
                handle.0,
                0,
                n,
                &PelageStrandEdits {
                    lengths: lengths.as_ptr(),
                    push_mask: std::ptr::null(),
                },
                &params,
                &curves_desc(&mut cut, None),
            ),
            "pelage_groom_expand_edited",
        );
        let mut cut_exact = vec![[0.0f32; 4]; n * per];
        ok(
            pelage_groom_expand_edited(
                groom,
                handle.0,
                0,
                n,
                &PelageStrandEdits {
                    lengths: exact.as_ptr(),
                    push_mask: std::ptr::null(),
                },
                &params,
                &curves_desc(&mut cut_exact, None),
            ),
            "pelage_groom_expand_edited",
        );
        let mut whole = vec![[0.0f32; 4]; n * per];
        ok(
            pelage_groom_expand(
                groom,
                handle.0,
                0,
                n,
                &params,
                &curves_desc(&mut whole, None),
            ),
            "pelage_groom_expand",
        );
        // a cut hair is the whole one up to its stored length
        for (i, (c, w)) in cut.chunks(per).zip(whole.chunks(per)).enumerate() {
            let u = lengths[i] as f32 / PELAGE_TRIM_WHOLE as f32 * (per - 1) as f32;
            let k = (u as usize).min(per - 2);
            let tip = Vec3::from_slice(&w[k]).lerp(Vec3::from_slice(&w[k + 1]), u - k as f32);
            assert!(
                tip.distance(Vec3::from_slice(&c[per - 1])) < 1e-4,
                "hair {i}"
            );
        }
        let view = mesh_view(cloth);
        let mut memory = vec![0u8; Body::required_bytes(&view).unwrap()];
        let shirt_body = Body::new(&view, &mut Arena::new(&mut memory)).unwrap();
        let skin = mesh_view(body);
        let under: Vec<bool> = fur
            .strands
            .iter()
            .map(|r| {
                let (face, u, v) = (r.face as usize, r.u, r.v);
                let (p, n) = (skin.point(face, u, v), skin.normal(face, u, v));
                shirt_body
                    .first_meet(p, p + n * 2.0 * GAP)
                    .is_some_and(|t| t > 0.25)
            })
            .collect();
        // hairs sandwiched under the shirt: it is 0.5 to 2 gaps off their root
        let sandwiched = |i: usize| trimmed[i] && under[i];
        crossed += crossings(&shirt_body, &cut, per, sandwiched);
        crossed_whole += crossings(&shirt_body, &whole, per, sandwiched);
        let inside = |i: usize| {
            let b = &fur.bindings[i];
            sandwiched(i)
                && (0..b.count as usize).all(|k| b.weights[k] == 0.0 || met[b.guides[k] as usize])
        };
        crossed_inside += crossings(&shirt_body, &cut, per, inside);
        crossed_exact += crossings(&shirt_body, &cut_exact, per, |_| true);
        let caps = capsules(&rest, &fur.guide_roots, f);
        for (i, w) in whole.chunks(per).enumerate() {
            if exact[i] == PELAGE_TRIM_WHOLE {
                continue;
            }
            let at = |x: f32| {
                let k = (x as usize).min(per - 2);
                Vec3::from_slice(&w[k]).lerp(Vec3::from_slice(&w[k + 1]), x - k as f32)
            };
            let u = exact[i] as f32 / PELAGE_TRIM_WHOLE as f32 * (per - 1) as f32;
            let (a, b) = (at(u), at((u + 1.0).min((per - 1) as f32)));
            let in_capsule = |p: Vec3| {
                caps.iter()
                    .any(|c| segment_distance(p, c.a.into(), c.b.into()) < c.radius)
            };
            reached[i] |= shirt_body.first_meet(a, b).is_some()
                || (1..=8).any(|s| in_capsule(a.lerp(b, s as f32 / 8.0)));
        }
        hairs_inside += (0..n).filter(|&i| inside(i)).count();
    }
    println!(
        "segments of trimmed hairs under the shirt crossing it, over the shot: {crossed} cut, \
         {crossed_whole} uncut; {crossed_inside} of hairs whose guides all met it \
         ({hairs_inside} hair-frames)"
    );
    let exact_trimmed = exact.iter().filter(|&&l| l < PELAGE_TRIM_WHOLE).count();
    println!(
        "the exact shot pass (each hair's own curve): {exact_trimmed} hairs trimmed; \
         segments of any hair crossing the shirt over the shot: {crossed_exact}"
    );
    // from the guides' records, interpolation between guides that meet the
    // shirt at different heights, and across its border, leaves some cut
    // hairs through it; the cut removes most crossings
    assert!(crossed_whole > 0, "uncut, the fur goes through the shirt");
    assert!(
        crossed * 3 < crossed_whole,
        "the cut removes most crossings"
    );
    assert_eq!(
        crossed_exact, 0,
        "no hair cut by its own curve crosses the shirt"
    );
    let cut_short = (0..n)
        .filter(|&i| exact[i] < PELAGE_TRIM_WHOLE && !reached[i])
        .count();
    println!("exactly cut hairs that meet nothing past their cut on any frame: {cut_short}");
    assert!(
        exact_trimmed > 0 && cut_short * 500 < exact_trimmed,
        "an exact cut is where a frame needs it ({cut_short} of {exact_trimmed} shorter)"
    );
    pelage_groom_free(groom);
}
