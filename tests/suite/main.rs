//! The integration tests, as one test binary (one link instead of eleven, which is most of
//! what the test command spends after the library is built). Each module is one subject;
//! `tests/allocations.rs` stays a binary of its own, because it installs a counting global
//! allocator.

#[path = "../common/mod.rs"]
mod common;

mod approximate;
mod area;
mod explore;
mod fuzz;
mod loading;
mod paper;
mod readme;
mod reflection;
mod shading;
mod shadows;
mod study;
mod visibility;
