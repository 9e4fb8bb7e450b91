//! Reports of runs: per-frame records with their averages, machine and build (`records`); the
//! paper's tables made of them are `crate::tables`, beside the bench that fills them.

pub mod records;
