//! # umbra
//!
//! The classic hidden-surface and shadow algorithms of the 1970s, reproduced exactly, made
//! fast, and measured against the z-buffer methods that replaced them.
//!
//! Data flows one way:
//!
//! ```text
//! Scene ──view──▶ screen polygons ──visibility──▶ runs per scanline
//!       ──shadow──▶ lit value per light sample ──shading──▶ Frame
//! ```
//!
//! What a program uses:
//!
//! - [`Scene`]: loaded from a TOML file ([`Scene::load`], the format of
//!   `docs/scene-format.md`), built from parts ([`Scene::new`] and the types of [`scene`]),
//!   or generated ([`generate`]).
//! - [`render()`] renders one frame; a [`Renderer`] renders many, each in the memory of the
//!   last (no frame-sized allocation after the first).
//! - [`RenderOptions`]: the [`VisibilityMethod`], the [`ShadowMethod`] with its settings (the
//!   types of [`shadow`]), the [`ReflectionMethod`].
//! - [`Rendered`]: the [`Frame`] (colour, face id and lit fraction per pixel, and their PNG
//!   encodings) and its [`Stats`] (the stages' [`Counters`] and times).
//! - [`Error`]: what went wrong, on one line, naming the file and line where there is one.
//!
//! And to study the algorithms: [`reference`](mod@reference) (the exact answer by ray casting, and the
//! definition of a tie), [`view`] (the camera's pixel-centre rule), [`visibility`] (one
//! visibility stage alone), [`shading`] (the illumination model) and [`study`] (the
//! `bench`, `compare`, `scale`, `trace` and `explore` tools). The algorithms themselves are
//! one private module each, named after their paper, documented in `docs/algorithms/`.
//!
//! ```
//! use umbra::{generate, render, RenderOptions, ShadowMethod, VisibilityMethod};
//!
//! let scene = generate::cubes(2, generate::Faces::Quads, 64, 48)?;
//! let opts = RenderOptions {
//!     visibility: VisibilityMethod::Scanline,
//!     shadows: ShadowMethod::RayCast,
//!     ..RenderOptions::default()
//! };
//! let out = render(&scene, &opts)?;
//! assert_eq!(out.frame.id.len(), 64 * 48);
//! println!("{}", serde_json::to_string(&out.stats).unwrap());
//! # Ok::<(), umbra::Error>(())
//! ```
#![warn(missing_docs)]
// No public signature holds a type a program cannot name.
#![warn(unnameable_types)]

mod budget;
mod bvh;
mod error;
mod frame;
pub mod generate;
mod geometry;
mod pieces;
mod pool;
mod progress;
mod raster;
pub mod reference;
mod reflection;
mod render;
mod scan;
pub mod scene;
pub mod shading;
pub mod shadow;
mod stats;
pub mod study;
pub mod view;
pub mod visibility;

pub use error::{Error, FileLoc, Result};
pub use frame::{check_gamma, Frame, PixelCounters, ShadeClass, BACKGROUND, GAMMA_RANGE};
/// The vector types the API takes and gives (points, directions, colours).
pub use glam;
/// The image types the API gives ([`Frame::color_image`], `study::compare::diff`): use
/// these, whatever version of `image` a program has of its own.
pub use image;
pub use progress::{Progress, ProgressFn};
pub use reflection::ReflectionMethod;
pub use render::{render, RenderOptions, Rendered, Renderer};
pub use scene::{Camera, Light, Material, Mesh, Object, Scene, SceneBuilder};
pub use shadow::ShadowMethod;
pub use stats::{Counter, Counters, Stats, Times};
pub use visibility::VisibilityMethod;
