//! Buffers that live across frames: from the second frame of a run on, the fixed-only
//! path (`pipeline::fast::Emulator`) allocates no frame-sized buffer, counted by a global
//! allocator that records every allocation (or growth) of at least one byte per pixel of
//! the screen. The first frame does allocate them (so the count can fail), and the codes
//! stay those of a one-shot run. One test per file: the counter sees the whole process.

use igemu::config::HwConfig;
use igemu::pipeline::fast::{self, Emulator};
use igemu::scene::Scene;
use igemu::stage::RunOptions;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

struct Counting;

static ON: AtomicBool = AtomicBool::new(false);
static LIMIT: AtomicUsize = AtomicUsize::new(usize::MAX);
static BIG: AtomicUsize = AtomicUsize::new(0);
/// The sizes of the first big allocations seen (for the failure message).
static SIZES: [AtomicUsize; 16] = [const { AtomicUsize::new(0) }; 16];

fn note(size: usize) {
    if ON.load(Ordering::Relaxed) && size >= LIMIT.load(Ordering::Relaxed) {
        let n = BIG.fetch_add(1, Ordering::Relaxed);
        if let Some(s) = SIZES.get(n) {
            s.store(size, Ordering::Relaxed);
        }
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size > layout.size() {
            note(new_size);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static A: Counting = Counting;

/// The tests of this file run one at a time: the allocation count is global.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

/// Big allocations while `f` runs.
fn count(f: impl FnOnce()) -> (usize, Vec<usize>) {
    BIG.store(0, Ordering::Relaxed);
    ON.store(true, Ordering::SeqCst);
    f();
    ON.store(false, Ordering::SeqCst);
    let n = BIG.load(Ordering::Relaxed);
    let sizes = SIZES[..n.min(SIZES.len())]
        .iter()
        .map(|s| s.load(Ordering::Relaxed))
        .collect();
    (n, sizes)
}

#[test]
fn from_the_second_frame_on_no_frame_sized_buffer_is_allocated() {
    let _one_at_a_time = serial();
    let plain = HwConfig::default_config();
    // The post stages too: an ordered dither after the LUT (its extended LUT is made once
    // per run, its output plane comes from the pool).
    let mut dithered = HwConfig::default_config();
    dithered.dither.kind = igemu::config::DitherKind::Bayer8;
    for (name, hw) in [
        ("default", &plain),
        ("default-pinhole", &plain),
        ("default-colour", &plain),
        ("default-pinhole", &dithered),
    ] {
        let scene = Scene::embedded(name).expect("embedded");
        let once = fast::emulate(&scene, hw, RunOptions::FIXED_ONLY, None).expect("runs");
        let g = once.plan.layout.grid;
        assert!(!once.channels[0].is_empty());
        let pixels = g.width as usize * g.height as usize;
        LIMIT.store(pixels, Ordering::Relaxed);
        let emu = Emulator::new();
        let mut same = Vec::new();
        let mut big = Vec::new();
        for _ in 0..3 {
            let (n, sizes) = count(|| {
                let e = emu
                    .emulate(&scene, hw, RunOptions::FIXED_ONLY, None)
                    .expect("runs");
                // Compared here (a copy would be a frame-sized allocation of its own).
                same.push(e.channels == once.channels);
                emu.recycle(e);
            });
            big.push((n, sizes));
        }
        assert!(big[0].0 > 0, "{name}: the first frame allocates its planes");
        for (f, (n, sizes)) in big.iter().enumerate().skip(1) {
            assert_eq!(
                *n, 0,
                "{name}: frame {f} allocated {n} buffers of at least {pixels} bytes: {sizes:?}"
            );
        }
        assert!(same.iter().all(|&s| s), "{name}: the pooled frames' codes");
    }
}

/// A pooled buffer keeps the last frame's values until a kernel overwrites them
/// (`Pool::scratch`): a frame after a different scene on the same emulator must still give
/// its own one-shot codes, so no kernel may leave a pixel unwritten.
#[test]
fn a_frame_after_another_scene_gives_its_own_codes() {
    let _one_at_a_time = serial();
    let plain = HwConfig::default_config();
    let mut bayer = HwConfig::default_config();
    bayer.dither.kind = igemu::config::DitherKind::Bayer8;
    let mut fs = HwConfig::default_config();
    fs.dither.kind = igemu::config::DitherKind::FloydSteinberg;
    for (label, hw) in [
        ("plain", &plain),
        ("bayer8", &bayer),
        ("floyd-steinberg", &fs),
    ] {
        let emu = Emulator::new();
        for name in ["default", "default-pinhole", "cone-focus", "default"] {
            let scene = Scene::embedded(name).expect("embedded");
            let once = fast::emulate(&scene, hw, RunOptions::FIXED_ONLY, None).expect("runs");
            let e = emu
                .emulate(&scene, hw, RunOptions::FIXED_ONLY, None)
                .expect("runs");
            assert!(
                e.channels == once.channels,
                "{label}: {name} after another scene on one emulator"
            );
            emu.recycle(e);
        }
    }
}
