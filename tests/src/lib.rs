pub mod creature;
