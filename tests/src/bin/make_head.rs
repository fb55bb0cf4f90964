//! `make_head <out_dir>`: write the head test mesh (`head.obj`, with `vt`
//! and `vn`) and its hair density map (`head_density.png`, 256x256, 8-bit
//! grayscale, white: fur everywhere) into `out_dir`; the conventions are
//! those of `make_creature`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use pelage_tests::creature::{sample_texture, write_obj, write_png_gray};
use pelage_tests::head::head_with_parts;

fn main() -> ExitCode {
    let mut args = std::env::args_os().skip(1);
    let (Some(out), None) = (args.next(), args.next()) else {
        eprintln!("usage: make_head <out_dir>");
        return ExitCode::from(2);
    };
    let out = PathBuf::from(out);
    match run(&out) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("make_head: {}: {e}", out.display());
            ExitCode::FAILURE
        }
    }
}

fn run(out: &Path) -> std::io::Result<()> {
    let t0 = Instant::now();
    std::fs::create_dir_all(out)?;
    let (mesh, parts) = head_with_parts();
    let obj = out.join("head.obj");
    write_obj(&mesh, &obj)?;
    let (w, h) = (256, 256);
    let png = out.join("head_density.png");
    write_png_gray(&png, w, h, &sample_texture(w, h, |_| 1.0))?;
    let (lo, hi) = mesh.bounds();
    println!("vertices:  {}", mesh.vertex_count());
    println!("triangles: {}", mesh.triangle_count());
    println!(
        "parts:     head {:?}, eyes {:?}, horn {:?}, ears {:?}",
        parts.head, parts.eyes, parts.horn, parts.ears
    );
    println!("bounds:    {lo:?} .. {hi:?}");
    println!("wrote {} and {} ({w}x{h})", obj.display(), png.display());
    println!("time:      {:.3} s", t0.elapsed().as_secs_f64());
    Ok(())
}
