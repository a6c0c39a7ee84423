//! Study and comparison tools: `umbra compare` (every method on one scene, against the
//! ray-cast reference, as an HTML report), `umbra scale` (cost against a scene parameter, as
//! CSV and plots), `umbra trace` (one scanline, step by step), and false-colour images of the
//! per-pixel counters.

pub mod compare;
pub mod false_colour;
pub mod scale;
pub mod trace;
