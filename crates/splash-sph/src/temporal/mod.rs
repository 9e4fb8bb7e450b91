//! Sequences over time (issue 38): the fluid's motion between frames ([`motion`]), surfaces
//! that follow it from frame to frame ([`filter`]), and the jitter of a sequence of surfaces
//! measured against it ([`jitter`]).

pub mod filter;
pub mod jitter;
pub mod motion;

pub use filter::{Followed, Neighbour, follow_fluid};

pub use jitter::{Jitter, Window, frame_jitter};
pub use motion::{FrameMotion, mean_motion};
