//! `make_creature <out_dir>`: write the default creature test mesh
//! (`creature.obj`) and its hair density map (`creature_density.png`,
//! 1024x512, 8-bit grayscale; texel (x, y) covers
//! uv = ((x + 0.5) / 1024, (y + 0.5) / 512), row 0 = v near 0) into `out_dir`.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use pelage_tests::creature::{default_creature, density_texture, write_obj, write_png_gray};

fn main() -> ExitCode {
    let mut args = std::env::args_os().skip(1);
    let (Some(out), None) = (args.next(), args.next()) else {
        eprintln!("usage: make_creature <out_dir>");
        return ExitCode::from(2);
    };
    let out = PathBuf::from(out);
    match run(&out) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("make_creature: {}: {e}", out.display());
            ExitCode::FAILURE
        }
    }
}

fn run(out: &std::path::Path) -> std::io::Result<()> {
    let t0 = Instant::now();
    std::fs::create_dir_all(out)?;
    let mesh = default_creature();
    let obj = out.join("creature.obj");
    write_obj(&mesh, &obj)?;
    let (w, h) = (1024, 512);
    let png = out.join("creature_density.png");
    write_png_gray(&png, w, h, &density_texture(w, h))?;
    let (lo, hi) = mesh.bounds();
    println!("vertices:  {}", mesh.vertex_count());
    println!("triangles: {}", mesh.triangle_count());
    println!("bounds:    {lo:?} .. {hi:?}");
    println!("wrote {} and {} ({w}x{h})", obj.display(), png.display());
    println!("time:      {:.3} s", t0.elapsed().as_secs_f64());
    Ok(())
}
