//! A small groom on a bumpy plane, for the structured fuzz targets: valid
//! files to damage, so the fuzzer reaches past the checksum into every check
//! of the decoders. Shared by both targets, which each use part of it.
#![allow(dead_code)]

use pelage_core::cache::groom_file::Groom;
use pelage_core::guides::{CvLayout, Guides};
use pelage_core::interp::bind::{StrandBinding, MAX_NEIGHBOURS};
use pelage_core::interp::groom::StrandGroom;
use pelage_core::interp::patch::Patch;
use pelage_core::interp::posed::PosedFrame;
use pelage_core::interp::strands::Strands;
use pelage_core::{Arena, ArenaLayout, Mesh, Root, Strided};

pub const N: usize = 8;
pub const POINTS: usize = 6;
pub const GUIDES: usize = 300;

pub struct Scene {
    pub guide_roots: Vec<Root>,
    pub rest_local: Vec<[f32; 3]>,
    pub roots: Vec<Root>,
    pub bindings: Vec<StrandBinding>,
    pub grooms: Vec<StrandGroom>,
}

/// A grid of N x N quads, lifted by `t`.
pub fn grid(t: f32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let mut p = vec![];
    for y in 0..=N {
        for x in 0..=N {
            let (u, v) = (x as f32 / N as f32, y as f32 / N as f32);
            p.push([u, v, 0.1 * (u * 6.0 + t).sin() * (v * 4.0).cos()]);
        }
    }
    let mut tri = vec![];
    let i = |x: usize, y: usize| (y * (N + 1) + x) as u32;
    for y in 0..N {
        for x in 0..N {
            tri.push([i(x, y), i(x + 1, y), i(x + 1, y + 1)]);
            tri.push([i(x, y), i(x + 1, y + 1), i(x, y + 1)]);
        }
    }
    (p, tri)
}

pub fn guide_roots() -> Vec<Root> {
    (0..GUIDES as u32)
        .map(|g| Root {
            face: g % (2 * N * N) as u32,
            u: 0.25,
            v: 0.5 * ((g * 7 % 10) as f32 / 10.0),
            id: g,
            rank: g,
        })
        .collect()
}

/// Guides straight up, swung by `t`.
pub fn guides(mesh: &Mesh, roots: &[Root], t: f32) -> Vec<[f32; 3]> {
    let mut out = vec![];
    for (g, r) in roots.iter().enumerate() {
        let p = mesh.point(r.face as usize, r.u, r.v);
        for j in 0..POINTS {
            let s = j as f32 / (POINTS - 1) as f32;
            let swing = t * s * s * (g as f32).sin();
            out.push([p.x + swing * 0.05, p.y - swing * 0.02, p.z + 0.1 * s]);
        }
    }
    out
}

/// Runs `f` on the plane at time `t`, posed.
pub fn with_frame<T>(t: f32, roots: &[Root], f: impl FnOnce(&PosedFrame) -> T) -> T {
    let (p, tri) = grid(t);
    let mesh = Mesh::new(Strided::from_slice(&p), Strided::from_slice(&tri));
    let points = guides(&mesh, roots, t);
    let g = Guides {
        roots,
        points: Strided::from_slice(&points),
        layout: CvLayout::Fixed(POINTS),
    };
    let mut layout = ArenaLayout::new();
    PosedFrame::layout(&mut layout, p.len(), roots.len(), POINTS);
    let mut buf = vec![0u8; layout.bytes()];
    let frame = PosedFrame::with_guides(mesh, &g, POINTS, &mut Arena::new(&mut buf)).unwrap();
    f(&frame)
}

/// Runs `f` on an empty frame of the plane at time `t`.
pub fn with_target<T>(t: f32, f: impl FnOnce(&mut PosedFrame) -> T) -> T {
    let (p, tri) = grid(t);
    let mesh = Mesh::new(Strided::from_slice(&p), Strided::from_slice(&tri));
    let mut layout = ArenaLayout::new();
    PosedFrame::layout(&mut layout, p.len(), GUIDES, POINTS);
    let mut buf = vec![0u8; layout.bytes()];
    let mut frame = PosedFrame::new(mesh, GUIDES, POINTS, &mut Arena::new(&mut buf)).unwrap();
    f(&mut frame)
}

impl Scene {
    pub fn new() -> Scene {
        let guide_roots = guide_roots();
        let rest_local = with_frame(0.0, &guide_roots, |f| f.local_points().collect());
        let roots: Vec<Root> = (0..50u32)
            .map(|i| Root {
                face: i,
                u: 0.3,
                v: 0.3,
                id: i,
                rank: i,
            })
            .collect();
        let bindings = (0..50u32)
            .map(|i| {
                let mut b = StrandBinding {
                    guides: [0; MAX_NEIGHBOURS],
                    weights: [0.0; MAX_NEIGHBOURS],
                    count: 2,
                    clump: i,
                };
                b.guides[..2].copy_from_slice(&[i, i + 1]);
                b.weights[..2].copy_from_slice(&[0.5, 0.5]);
                b
            })
            .collect();
        let grooms = vec![
            StrandGroom {
                length: 1.0,
                root_radius: 0.01,
                tip_radius: 0.001,
                clump: 0.2,
                kink_phase: [1.0, 0.0],
                ..StrandGroom::default()
            };
            50
        ];
        Scene {
            guide_roots,
            rest_local,
            roots,
            bindings,
            grooms,
        }
    }

    pub fn groom(&self) -> Groom<'_> {
        Groom {
            guide_roots: &self.guide_roots,
            guide_points: &self.rest_local,
            points: POINTS,
            strands: Strands {
                roots: &self.roots,
                bindings: &self.bindings,
                grooms: &self.grooms,
            },
            patches: &[
                Patch {
                    first: 0,
                    count: 20,
                },
                Patch {
                    first: 20,
                    count: 30,
                },
            ],
        }
    }
}

/// Applies the fuzzer's edits to a valid file: (offset u16, xor byte)
/// triples, then (when `reseal`) rewrites the CRC at `crc_at` so the edits
/// reach the decoder's own checks.
pub fn damage(bytes: &mut Vec<u8>, edits: &[u8], crc_at: usize, reseal: bool) {
    for e in edits.chunks_exact(3) {
        let at = u16::from_le_bytes([e[0], e[1]]) as usize;
        match e[2] {
            // truncate
            0 => bytes.truncate(at.min(bytes.len())),
            x => {
                let len = bytes.len().max(1);
                if let Some(b) = bytes.get_mut(at % len) {
                    *b ^= x;
                }
            }
        }
    }
    if reseal && bytes.len() >= crc_at + 8 {
        let mut h = crc32fast::Hasher::new();
        h.update(&bytes[..crc_at]);
        h.update(&bytes[crc_at + 8..]);
        let crc = h.finalize().to_le_bytes();
        bytes[crc_at..crc_at + 4].copy_from_slice(&crc);
    }
}
