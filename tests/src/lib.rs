//! Test assets and helpers shared by pelage's end-to-end tests and benchmarks.

pub mod animated;
pub mod corpus;
pub mod creature;
pub mod head;
pub mod measure;
pub mod quality;
