//! A program renders the same scene many times through one `Renderer` with no frame-sized
//! allocation after the first frame: the frame's buffers, the z-buffer's and the shadow
//! maps are reused. Counted with a global allocator that notes every allocation (and
//! growth) of at least one byte per pixel; this test binary has no other tests, so nothing
//! else allocates while it counts.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use umbra::{generate, RenderOptions, Renderer, ShadowMethod, VisibilityMethod};

struct Counting;

/// Allocations of at least `LARGE` bytes so far.
static LARGE_ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);
/// What counts as frame-sized: one byte per pixel of the test's frame.
static LARGE: AtomicUsize = AtomicUsize::new(usize::MAX);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if layout.size() >= LARGE.load(Ordering::Relaxed) {
            LARGE_ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if layout.size() >= LARGE.load(Ordering::Relaxed) {
            LARGE_ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size >= LARGE.load(Ordering::Relaxed) {
            LARGE_ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

#[test]
fn a_renderer_allocates_no_frame_sized_buffer_after_its_first_frame() {
    let (w, h) = (320u32, 240u32);
    let mut scene = generate::cubes(4, generate::Faces::Quads, w, h).unwrap();
    // Blinn's planar shadows need a receiver: the floor.
    assert!(!scene.mark_planar_receivers().is_empty());
    LARGE.store((w * h) as usize, Ordering::Relaxed);
    // Every stage the engine lists, behind both visibility stages: many frames of the plain
    // frame, twenty of each shadow stage.
    let mut methods = Vec::new();
    for visibility in [VisibilityMethod::Scanline, VisibilityMethod::ZBuffer] {
        for shadows in ShadowMethod::ALL {
            let frames = if shadows == ShadowMethod::None { 100 } else { 20 };
            methods.push((visibility, shadows, frames));
        }
    }
    for (visibility, shadows, frames) in methods {
        let opts = RenderOptions { visibility, shadows: shadows.clone(), ..RenderOptions::default() };
        let mut renderer = Renderer::new();
        let first = LARGE_ALLOCATIONS.load(Ordering::Relaxed);
        renderer.render(&scene, &opts).unwrap();
        let after_first = LARGE_ALLOCATIONS.load(Ordering::Relaxed);
        assert!(after_first > first, "{visibility} + {shadows}: the first frame allocates its buffers");
        for _ in 1..frames {
            let out = renderer.render(&scene, &opts).unwrap();
            assert_eq!(out.frame.id.len(), (w * h) as usize);
        }
        let more = LARGE_ALLOCATIONS.load(Ordering::Relaxed) - after_first;
        assert_eq!(more, 0, "{visibility} + {shadows}: {more} frame-sized allocations after the first frame");
        // A fresh renderer allocates again: the count sees what it should.
        let before = LARGE_ALLOCATIONS.load(Ordering::Relaxed);
        umbra::render(&scene, &opts).unwrap();
        assert!(LARGE_ALLOCATIONS.load(Ordering::Relaxed) > before);
    }
    // Mirrors: each mirror's frame, and the ids seen in it, come from the renderer too.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mirror.toml");
    let mut scene = umbra::Scene::load(path).unwrap();
    let mut camera = scene.camera().clone();
    (camera.width, camera.height) = (w, h);
    scene.set_camera(camera).unwrap();
    for reflection in [umbra::ReflectionMethod::ReflectScene, umbra::ReflectionMethod::ReflectEye] {
        let opts = RenderOptions { reflection, ..RenderOptions::default() };
        let mut renderer = Renderer::new();
        assert!(renderer.render(&scene, &opts).unwrap().frame.mirror_id.is_some(), "a mirror is seen");
        let after_first = LARGE_ALLOCATIONS.load(Ordering::Relaxed);
        for _ in 1..10 {
            renderer.render(&scene, &opts).unwrap();
        }
        let more = LARGE_ALLOCATIONS.load(Ordering::Relaxed) - after_first;
        assert_eq!(more, 0, "mirrors ({reflection:?}): {more} frame-sized allocations after the first frame");
    }
}
