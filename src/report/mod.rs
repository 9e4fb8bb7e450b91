//! Reports of runs: per-frame records with their averages, machine and build (`records`), and
//! the paper's Tables 1, 3/4 and 5/6 made of them (`tables`).

pub mod records;
pub mod tables;
