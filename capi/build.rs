//! Regenerates include/pelage.h, and the same declarations in the form
//! cffi reads (python/pelage/_cdef.h, from cbindgen-cffi.toml), from the
//! crate's sources on every build, so the committed files can be checked for
//! drift, and gives the shared library its SONAME.

use std::path::{Path, PathBuf};

fn main() {
    let crate_dir = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap());
    let header = crate_dir.join("..").join("include").join("pelage.h");
    println!("cargo:rerun-if-changed=src");
    println!("cargo:rerun-if-changed=cbindgen.toml");
    println!("cargo:rerun-if-changed=cbindgen-cffi.toml");
    generate(&crate_dir, "cbindgen.toml", &header);
    let cdef = crate_dir
        .join("..")
        .join("python")
        .join("pelage")
        .join("_cdef.h");
    if cdef.parent().is_some_and(|dir| dir.is_dir()) {
        println!("cargo:rerun-if-changed={}", cdef.display());
        generate(&crate_dir, "cbindgen-cffi.toml", &cdef);
    }
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux") {
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,{}", soname());
    }
}

/// Writes the declarations cbindgen makes with the configuration `config`
/// (a file beside this one) to `out`; cbindgen leaves an unchanged file alone.
fn generate(crate_dir: &Path, config: &str, out: &Path) {
    let config = cbindgen::Config::from_file(crate_dir.join(config)).expect(config);
    cbindgen::Builder::new()
        .with_crate(crate_dir)
        .with_config(config)
        .generate()
        .expect("cbindgen could not generate the header")
        .write_to_file(out);
}

/// The shared library's SONAME: before 1.0 a minor release may break the
/// ABI, so it names major and minor (libpelage.so.0.6); from 1.0 the major.
fn soname() -> String {
    let major = std::env::var("CARGO_PKG_VERSION_MAJOR").unwrap();
    let minor = std::env::var("CARGO_PKG_VERSION_MINOR").unwrap();
    match major.as_str() {
        "0" => format!("libpelage.so.0.{minor}"),
        _ => format!("libpelage.so.{major}"),
    }
}
