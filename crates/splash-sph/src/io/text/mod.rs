//! Text in and out of the text formats: the lines of a text input, read with their numbers
//! for error messages ([`lines`]), and the numbers of a text output, formatted far faster than
//! `fmt` ([`float_text`], with [`decimal_lanes`] its AVX-512 path) on all threads
//! ([`text_records`]).

mod decimal_lanes;
pub(super) mod float_text;
pub(super) mod lines;
pub(super) mod text_records;
