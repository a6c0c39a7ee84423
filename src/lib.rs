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
//! - [`scene`]: the scene file of `docs/scene-format.md` (TOML + OBJ), compiled to world polygons.
//! - [`view`]: camera, pixel-centre rule, near/far clipping, projection.
//! - [`scan`]: the edge table and active edge table every scanline stage walks.
//! - [`visibility`]: Watkins' scanline algorithm, the z-buffer, and a ray-cast reference.
//! - [`shadow`]: the shadow stages behind one trait.
//! - [`shading`]: the illumination model.
//! - [`frame`]: the image and its analysis buffers.
//! - [`render()`] renders one frame; a [`Renderer`] renders many, each in the memory of the
//!   last (no frame-sized allocation after the first).
//!
//! ```
//! use umbra::{generate, render, RenderOptions, ShadowMethod, VisibilityMethod};
//!
//! let scene = generate::cubes(2, false, 64, 48)?;
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

pub mod budget;
pub mod bvh;
pub mod error;
pub mod frame;
pub mod generate;
pub mod geometry;
mod pool;
mod progress;
mod raster;
pub mod reference;
pub mod reflection;
pub mod render;
pub mod scan;
pub mod scene;
pub mod shading;
pub mod shadow;
pub mod stats;
pub mod study;
pub mod view;
pub mod visibility;

pub use error::{Error, FileLoc, Result};
pub use frame::Frame;
pub use render::{render, RenderOptions, Rendered, Renderer};
pub use scene::Scene;
pub use shadow::ShadowMethod;
pub use stats::{Counters, Stats};
pub use visibility::VisibilityMethod;
