//! Per-frame records.
