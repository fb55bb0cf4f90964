//! The stamp on the corpus of production-like meshes (see
//! `pelage_tests::corpus`): a row per mesh and the worst, at 20,000 roots;
//! `PELAGE_CORPUS=representative` for the 4 coarse meshes only.
//!
//!   cargo bench -p pelage-tests --bench stamp_corpus

use pelage_tests::corpus;

fn main() {
    let list = match std::env::var("PELAGE_CORPUS").as_deref() {
        Ok("representative") => corpus::representative(),
        _ => corpus::corpus(),
    };
    println!(
        "## The stamp on the corpus ({} roots, 1 thread)\n",
        corpus::report::TARGET
    );
    corpus::report::stamp_table(list);
}
