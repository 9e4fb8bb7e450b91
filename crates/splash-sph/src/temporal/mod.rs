//! Sequences over time (issue 38): the fluid's motion between frames ([`FrameMotion`]), surfaces
//! that follow it from frame to frame (`post.temporal` in a sequence, and
//! [`surface_following`](crate::pipeline::surface_following): [`Followed`]), and the jitter of a
//! sequence of surfaces measured against it ([`frame_jitter`]).

mod filter;
mod jitter;
mod motion;

pub use filter::Followed;
pub(crate) use filter::{Neighbour, carry, follow_carried, follow_fluid, neighbour_bins};

pub use jitter::{DROPLET, Jitter, PARTS, Part, Window, frame_jitter};
pub use motion::FrameMotion;
