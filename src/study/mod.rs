//! Study and comparison tools: `umbra bench` (each method's frame and phases, timed with
//! warm-up, median and spread), `umbra compare` (every method on one scene, against the
//! ray-cast reference, as an HTML report), `umbra scale` (cost against a scene parameter, as
//! CSV and plots), `umbra trace` (one scanline, step by step), `umbra explore` (the same,
//! drawn in a browser page), and false-colour images of the per-pixel counters.

pub mod bench;
pub mod compare;
#[cfg(feature = "explore")]
pub mod explore;
pub mod false_colour;
pub mod scale;
pub mod trace;
