//! Firmware test for Cortex-M4F (QEMU `mps2-an386`, or real hardware with `--features rtt`).
//!
//! Integrates the committed test vector (`vector/frames.bin`: 4 labelled depth frames of
//! 160x120 of a synthetic room corner, written by `sndt testvector`) into a
//! `static` `Map<4096, 512, 40>`, ray casts the vector's probe pixels, renders a 64x48 view
//! of the map from the last frame's pose (in bands of rows, into small stack buffers), and
//! reports over defmt: per-frame SysTick ticks, voxels, blocks, evictions, the snapshot CRC
//! (which must equal `vector/expected_crc.txt`, the host's CRC for the same frames), the
//! view's label histogram and CRC (which must equal `vector/expected_render_crc.txt`).
//!
//! Then the spill run (`spill.rs`): the same static map, reset to 9 cm cells, integrates
//! the frames again and overflows; every voxel and block it evicts goes out over UART0
//! (`uart.rs`, the board's CMSDK APB UART at 921,600 baud) as the core's record stream,
//! followed by the map's last content and the end frame. It reports per frame the records
//! spilled and dropped and the stream bytes, the totals, whether the stream fits the UART
//! at 10 frames/s, and the device map's CRC; scripts/firmware.sh merges the stream on the
//! host and checks it against `vector/expected_spill_crc.txt`.
//!
//! Last, static RAM and the peak stack (cortex-m-rt `paint-stack`). Exit status 0
//! (semihosting) only when every check passes; a panic or HardFault exits non-zero.
#![no_std]
#![no_main]

mod spill;
mod uart;
mod vector;

use core::cell::RefCell;

use cortex_m::interrupt::{self, Mutex};
use cortex_m::peripheral::{syst::SystClkSource, DWT, SYST};
use cortex_m_rt::{entry, exception, ExceptionFrame, STACK_PAINT_VALUE};
use cortex_m_semihosting::debug::{self, EXIT_FAILURE, EXIT_SUCCESS};
#[cfg(feature = "rtt")]
use defmt_rtt as _;
#[cfg(not(feature = "rtt"))]
use defmt_semihosting as _;
use heapless::Vec;
use sndt_core::{
    pose_from_matrix, Config, Crc32, Depth, DepthImage, DepthKind, FrameReport, Isometry3,
    LabelImage, Map, Matrix3, Phase, Pinhole, Point3, RayHit, Vector3, INVALID_LABEL,
};
use vector::{Frame, Vector};

const VOXELS: usize = 4096;
const BLOCKS: usize = 512;
const CLASSES: usize = 40;
type FwMap = Map<VOXELS, BLOCKS, CLASSES>;

/// The whole map lives in one zero-initialised static (`.bss`: no flash copy); `run`
/// installs its config with `Map::reset`.
static MAP: Mutex<RefCell<FwMap>> = Mutex::new(RefCell::new(FwMap::zeroed()));

/// The test vector in flash, 4-byte aligned so depth images are read as `&[f32]` in place.
#[repr(C, align(4))]
struct Aligned<T: ?Sized>(T);
static VECTOR: &Aligned<[u8]> = &Aligned(*include_bytes!("../vector/frames.bin"));
/// The host's snapshot CRC for the vector (`sndt testvector`).
const EXPECTED_CRC: &str = include_str!("../vector/expected_crc.txt");
/// The host's CRC of the rendered view (`sndt testvector`).
const EXPECTED_RENDER_CRC: &str = include_str!("../vector/expected_render_crc.txt");

/// Distance tolerance of a probe, metres (as `sndt testvector`).
const T_TOL: f32 = 0.15;
/// Stack headroom that must stay painted: less means the stack (nearly) ran into `.bss`.
const STACK_MARGIN: usize = 256;

#[entry]
fn main() -> ! {
    let mut ok = match cortex_m::Peripherals::take() {
        Some(mut p) => {
            // Two clocks per frame. DWT CYCCNT: core cycles on hardware (QEMU reads 0).
            p.DCB.enable_trace();
            DWT::unlock();
            p.DWT.enable_cycle_counter();
            // SysTick as a free-running 24-bit down-counter on the core clock (no interrupt):
            // cycles on hardware (up to 2^24); in QEMU with `-icount shift=0` one tick is
            // 40 instructions (25 MHz virtual clock, 1 ns per instruction).
            let mut syst = p.SYST;
            syst.set_clock_source(SystClkSource::Core);
            syst.set_reload(0x00ff_ffff);
            syst.clear_current();
            syst.enable_counter();
            let mut uart = uart::Uart::take(uart::BAUDDIV_921600);
            interrupt::free(
                |cs| match (MAP.borrow(cs).try_borrow_mut(), uart.as_mut()) {
                    (Ok(mut map), Some(uart)) => run(&mut map, &mut syst, uart).unwrap_or(false),
                    _ => false,
                },
            )
        }
        None => false,
    };
    ok &= stack_report();
    if ok {
        defmt::println!("sndt firmware: PASS");
        debug::exit(EXIT_SUCCESS);
    } else {
        defmt::println!("sndt firmware: FAIL");
        debug::exit(EXIT_FAILURE);
    }
    loop {
        cortex_m::asm::bkpt();
    }
}

/// SysTick ticks elapsed since `start` (a previous `SYST::get_current()`), or `None` if the
/// counter wrapped (more than 2^24 ticks).
fn ticks_since(syst: &mut SYST, start: u32) -> Option<u32> {
    let now = SYST::get_current();
    if syst.has_wrapped() {
        None
    } else {
        Some(start.wrapping_sub(now) & 0x00ff_ffff)
    }
}

/// The vector is broken (or does not fit the firmware): the run stops at once and fails.
struct Abort;

/// Integrates the vector, casts its probes, checks the map's CRC and the view's, then
/// runs the spill over `uart`: `Ok(true)` when every check passes.
fn run(map: &mut FwMap, syst: &mut SYST, uart: &mut uart::Uart) -> Result<bool, Abort> {
    let v = load_vector(map)?;
    let frames_ok = integrate_frames(map, syst, &v)?;
    if cfg!(feature = "frames-only") {
        return Ok(frames_ok);
    }
    let probes_ok = check_probes(map, &v)?;
    let map_ok = check_map(map, &v)?;
    let view_ok = check_view(map, syst, &v)?;
    let spill_ok = spill::run(map, &v, uart)?;
    Ok(frames_ok & probes_ok & map_ok & view_ok & spill_ok)
}

/// Parses the vector in flash and installs its cell size in the map.
fn load_vector(map: &mut FwMap) -> Result<Vector<'static>, Abort> {
    let v = Vector::parse(&VECTOR.0, VOXELS, BLOCKS, CLASSES).map_err(|e| {
        defmt::error!("test vector: {}", e);
        Abort
    })?;
    if map.reset(Config::with_cell_size(v.cell_size)).is_err() {
        defmt::error!("test vector: invalid cell size {=f32}", v.cell_size);
        return Err(Abort);
    }
    defmt::println!(
        "map: Map<{=usize}, {=usize}, {=usize}> = {=usize} bytes ({=usize} per voxel); vector: {=usize} frames of {=u32}x{=u32}, cell {=f32} m",
        VOXELS,
        BLOCKS,
        CLASSES,
        FwMap::BYTES,
        FwMap::VOXEL_BYTES,
        v.frames,
        v.camera.width,
        v.camera.height,
        v.cell_size
    );
    Ok(v)
}

/// The camera-to-world pose of a frame, if its rotation is one.
fn frame_pose(f: &Frame<'_>) -> Option<Isometry3<f32>> {
    let r = &f.rotation;
    let rot = Matrix3::new(r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8]);
    let t = Vector3::new(f.translation[0], f.translation[1], f.translation[2]);
    pose_from_matrix(&rot, &t).ok()
}

/// Frame `k`'s pose and its depth image with labels (borrowed from the vector in flash).
fn frame_input<'a>(v: &Vector<'a>, k: usize) -> Result<(Isometry3<f32>, DepthImage<'a>), Abort> {
    let f = v.frame(k).map_err(|e| {
        defmt::error!("frame {=usize}: {}", k, e);
        Abort
    })?;
    let Some(pose) = frame_pose(&f) else {
        defmt::error!("frame {=usize}: invalid pose", k);
        return Err(Abort);
    };
    let image = DepthImage {
        camera: v.camera,
        depth: Depth::Metres(f.depth),
        kind: DepthKind::Planar,
        labels: LabelImage::Top1(f.labels),
        stride: 1,
    };
    Ok((pose, image))
}

/// How long one call took: SysTick ticks (`None` if the counter wrapped) and DWT cycles.
struct Timing {
    ticks: Option<u32>,
    cycles: u32,
}

/// Runs `f`, timed by both clocks.
fn timed<T>(syst: &mut SYST, f: impl FnOnce() -> T) -> (T, Timing) {
    let _ = syst.has_wrapped(); // clears COUNTFLAG
    let (start, c0) = (SYST::get_current(), DWT::cycle_count());
    let result = f();
    let cycles = DWT::cycle_count().wrapping_sub(c0);
    let ticks = ticks_since(syst, start);
    (result, Timing { ticks, cycles })
}

/// Integrates every frame of the vector, reporting each and the mean times; false when a
/// frame failed or had points rejected.
fn integrate_frames(map: &mut FwMap, syst: &mut SYST, v: &Vector<'_>) -> Result<bool, Abort> {
    let mut ok = true;
    let (mut total_ticks, mut total_cycles) = (0u32, 0u32);
    let mut phases = [0u32; 5];
    for k in 0..v.frames {
        let (pose, image) = frame_input(v, k)?;
        let (result, time) = timed(syst, || integrate_observed(map, &pose, &image, &mut phases));
        total_cycles = total_cycles.saturating_add(time.cycles);
        match result {
            Ok(rep) => {
                report_frame(k, &rep, &time);
                match time.ticks {
                    Some(t) => total_ticks = total_ticks.saturating_add(t),
                    None => defmt::warn!("frame {=usize}: SysTick wrapped, no timing", k),
                }
                if rep.rejected_label != 0 || rep.rejected_out_of_range != 0 {
                    defmt::error!("frame {=usize}: points were rejected", k);
                    ok = false;
                }
            }
            Err(e) => {
                defmt::error!("frame {=usize}: integrate_depth: {}", k, e);
                ok = false;
            }
        }
    }
    let frames = v.frames.max(1) as u32;
    let per = |p: Phase| phases[p as usize] / frames;
    defmt::println!(
        "systick per frame by phase: points {=u32}, accumulate {=u32}, end voxels {=u32}, free space {=u32}",
        per(Phase::Points),
        per(Phase::Accumulate),
        per(Phase::EndVoxels),
        per(Phase::FreeSpace)
    );
    defmt::println!(
        "systick per frame {=u32}, dwt cycles per frame {=u32} (means over {=u32} frames; cycles are 0 without a cycle counter, as in QEMU)",
        total_ticks / frames,
        total_cycles / frames,
        frames
    );
    Ok(ok)
}

/// `Map::integrate_depth`, adding the SysTick ticks of each integration phase to `phases`
/// (indexed by `Phase as usize`; the counter counts down and wraps at 2^24).
fn integrate_observed(
    map: &mut FwMap,
    pose: &Isometry3<f32>,
    image: &DepthImage<'_>,
    phases: &mut [u32; 5],
) -> Result<FrameReport, sndt_core::Error> {
    let mut last = SYST::get_current();
    let mut current: Option<Phase> = None;
    map.integrate_depth_observed(pose, image, |p| {
        let now = SYST::get_current();
        if let Some(c) = current {
            let ticks = last.wrapping_sub(now) & 0x00ff_ffff;
            phases[c as usize] = phases[c as usize].saturating_add(ticks);
        }
        (last, current) = (now, Some(p));
    })
}

/// One line per integrated frame.
fn report_frame(k: usize, rep: &FrameReport, time: &Timing) {
    defmt::println!(
        "frame {=usize}: points {=u32}, end voxels {=u32}, rays {=u32}, voxels +{=u32} -{=u32}, blocks +{=u32} -{=u32}, dropped {=u32}/{=u32}, systick {=u32}, dwt cycles {=u32}",
        k,
        rep.points_used,
        rep.end_voxels,
        rep.rays,
        rep.voxels_created,
        rep.voxels_evicted,
        rep.blocks_created,
        rep.blocks_evicted,
        rep.dropped_points,
        rep.dropped_misses,
        time.ticks.unwrap_or(u32::MAX),
        time.cycles
    );
}

/// Most probes the firmware checks (the committed vector has 8).
const MAX_PROBES: usize = 16;

/// A probe pixel's ray cast into the map, and what the vector's frame saw there.
struct Probe {
    frame: usize,
    col: u32,
    row: u32,
    hit: Option<RayHit>,
    want_t: f32,
    want_class: u8,
}

/// Casts the ray of every probe pixel from its frame's pose.
fn cast_probes(map: &FwMap, v: &Vector<'_>) -> Result<Vec<Probe, MAX_PROBES>, Abort> {
    let mut probes = Vec::new();
    for i in 0..v.probes {
        let (k, col, row) = v.probe(i).ok_or(Abort)?;
        let Ok(f) = v.frame(k) else {
            defmt::error!("probe {=usize}: no frame {=usize}", i, k);
            return Err(Abort);
        };
        let pose = frame_pose(&f).ok_or(Abort)?;
        let ray = v.camera.ray(col, row);
        let ray = Vector3::new(ray[0], ray[1], ray[2]);
        let px = (row * v.camera.width + col) as usize;
        let (Some(&depth), Some(&class)) = (f.depth.get(px), f.labels.get(px)) else {
            defmt::error!(
                "probe {=usize}: pixel {=u32},{=u32} outside the image",
                i,
                col,
                row
            );
            return Err(Abort);
        };
        let origin = Point3::from(pose.translation.vector);
        let probe = Probe {
            frame: k,
            col,
            row,
            hit: map.raycast(&origin, &(pose.rotation * ray), 10.0),
            want_t: depth * ray.norm(),
            want_class: class,
        };
        if probes.push(probe).is_err() {
            defmt::error!("test vector: more than {=usize} probes", MAX_PROBES);
            return Err(Abort);
        }
    }
    Ok(probes)
}

/// Checks that every probe hits the surface its frame saw, within [`T_TOL`] and with its
/// class.
fn check_probes(map: &FwMap, v: &Vector<'_>) -> Result<bool, Abort> {
    let mut ok = true;
    for (i, p) in cast_probes(map, v)?.iter().enumerate() {
        let Some(hit) = p.hit else {
            defmt::error!("probe {=usize}: no hit", i);
            ok = false;
            continue;
        };
        let good = (hit.t - p.want_t).abs() < T_TOL && hit.class == p.want_class;
        defmt::println!(
            "probe {=usize} (frame {=usize}, pixel {=u32},{=u32}): t {=f32} (expected {=f32}), class {=u8} (expected {=u8}) {=str}",
            i,
            p.frame,
            p.col,
            p.row,
            hit.t,
            p.want_t,
            hit.class,
            p.want_class,
            if good { "ok" } else { "WRONG" }
        );
        ok &= good;
    }
    Ok(ok)
}

/// Reports the map's totals and checks its snapshot CRC against the host's.
fn check_map(map: &FwMap, v: &Vector<'_>) -> Result<bool, Abort> {
    let stats = map.stats();
    let (voxels, blocks) = (map.len(), map.block_count());
    defmt::println!(
        "voxels {=usize}, blocks {=usize}, frames {=u32}, evictions: voxels {=u64} blocks {=u64}",
        voxels,
        blocks,
        stats.frames,
        stats.voxels_evicted,
        stats.blocks_evicted
    );
    let crc = map.checksum();
    let Some(expected) = vector::parse_crc(EXPECTED_CRC) else {
        defmt::error!("vector/expected_crc.txt is not 0x........");
        return Err(Abort);
    };
    defmt::println!(
        "snapshot crc {=u32:#010x} (expected {=u32:#010x}) {=str}",
        crc,
        expected,
        if crc == expected { "ok" } else { "MISMATCH" }
    );
    Ok(crc == expected && stats.frames == v.frames as u32)
}

/// Size of the rendered view, pixels (as the host's `embedded::view`).
const VIEW_WIDTH: u32 = 64;
const VIEW_HEIGHT: u32 = 48;
/// Rows rendered per `render_rows` call: a band's buffers take 5 bytes per pixel of stack.
const BAND_ROWS: u32 = 8;
const BAND_PIXELS: usize = (VIEW_WIDTH * BAND_ROWS) as usize;

/// The view's camera: the vector's scaled to 64x48, principal point at the centre (the
/// same `f32` operations as the host, so the same bits).
fn view_camera(c: &Pinhole) -> Pinhole {
    Pinhole {
        fx: c.fx * VIEW_WIDTH as f32 / c.width as f32,
        fy: c.fy * VIEW_HEIGHT as f32 / c.height as f32,
        cx: VIEW_WIDTH as f32 / 2.0,
        cy: VIEW_HEIGHT as f32 / 2.0,
        width: VIEW_WIDTH,
        height: VIEW_HEIGHT,
    }
}

/// What the rendered view shows: pixels per label (index `CLASSES + 1` counts misses) and
/// the CRC of its pixels (label byte, then the distance's little-endian bytes).
struct View {
    pixels_per_label: [u32; CLASSES + 2],
    crc: u32,
}

/// Renders the view from the last frame's pose band by band; `None` if a band failed.
fn render_view(map: &FwMap, pose: &Isometry3<f32>, camera: &Pinhole) -> Option<View> {
    let mut pixels_per_label = [0u32; CLASSES + 2];
    let mut crc = Crc32::new();
    let (mut labels, mut distance) = ([0u8; BAND_PIXELS], [0f32; BAND_PIXELS]);
    for first_row in (0..VIEW_HEIGHT).step_by(BAND_ROWS as usize) {
        if let Err(e) = map.render_rows(pose, camera, first_row, &mut labels, &mut distance) {
            defmt::error!("render_rows from row {=u32}: {}", first_row, e);
            return None;
        }
        for (&l, d) in labels.iter().zip(&distance) {
            let bin = if l == INVALID_LABEL {
                CLASSES + 1
            } else {
                (l as usize).min(CLASSES)
            };
            if let Some(n) = pixels_per_label.get_mut(bin) {
                *n += 1;
            }
            crc.update(&[l]);
            crc.update(&d.to_le_bytes());
        }
    }
    Some(View {
        pixels_per_label,
        crc: crc.finish(),
    })
}

/// Renders the view, reports its histogram and time, and checks its CRC against the host's.
fn check_view(map: &FwMap, syst: &mut SYST, v: &Vector<'_>) -> Result<bool, Abort> {
    let last = v.frames.checked_sub(1).ok_or(Abort)?;
    let f = v.frame(last).map_err(|_| Abort)?;
    let pose = frame_pose(&f).ok_or(Abort)?;
    let camera = view_camera(&v.camera);
    let (view, time) = timed(syst, || render_view(map, &pose, &camera));
    let Some(view) = view else {
        return Ok(false);
    };
    for (label, &n) in view.pixels_per_label.iter().enumerate() {
        match (n, label) {
            (0, _) => {}
            (_, l) if l == CLASSES + 1 => defmt::println!("view: no hit {=u32} pixels", n),
            _ => defmt::println!("view: class {=usize} {=u32} pixels", label, n),
        }
    }
    defmt::println!(
        "view {=u32}x{=u32} from frame {=usize}: systick {=u32}, dwt cycles {=u32}",
        VIEW_WIDTH,
        VIEW_HEIGHT,
        last,
        time.ticks.unwrap_or(u32::MAX),
        time.cycles
    );
    let Some(expected) = vector::parse_crc(EXPECTED_RENDER_CRC) else {
        defmt::error!("vector/expected_render_crc.txt is not 0x........");
        return Err(Abort);
    };
    defmt::println!(
        "render crc {=u32:#010x} (expected {=u32:#010x}) {=str}",
        view.crc,
        expected,
        if view.crc == expected {
            "ok"
        } else {
            "MISMATCH"
        }
    );
    Ok(view.crc == expected)
}

/// Reports static RAM and the peak stack, and checks the stack kept some paint.
fn stack_report() -> bool {
    extern "C" {
        static _ram_start: u32;
        static _ram_end: u32;
        static _stack_start: u32;
        static _stack_end: u32;
    }
    // Addresses of linker symbols only (taking them is safe; nothing is read through them).
    let ram_start = &raw const _ram_start as usize;
    let ram_end = &raw const _ram_end as usize;
    let top = &raw const _stack_start as usize;
    let bottom = &raw const _stack_end as usize;
    // cortex-m-rt's `paint-stack` filled [bottom, top) with STACK_PAINT_VALUE before `main`;
    // the lowest word that lost its paint is the deepest the stack has reached.
    let mut p = bottom;
    while p < top {
        // SAFETY: `p` is 4-byte aligned (cortex-m-rt aligns `_stack_end`) and inside the
        // stack region in RAM, which is always readable; a volatile read of a `u32` there
        // has no side effects.
        let word = unsafe { core::ptr::read_volatile(p as *const u32) };
        if word != STACK_PAINT_VALUE {
            break;
        }
        p += 4;
    }
    let (static_ram, stack, peak) = (bottom - ram_start, top - bottom, top - p);
    defmt::println!(
        "static RAM {=usize} bytes, peak stack {=usize} bytes (of {=usize}), RAM budget {=usize} bytes",
        static_ram,
        peak,
        stack,
        ram_end - ram_start
    );
    let ok = peak + STACK_MARGIN <= stack;
    if !ok {
        defmt::error!(
            "the stack reached within {=usize} bytes of .bss",
            STACK_MARGIN
        );
    }
    ok
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic: {}", defmt::Display2Format(info));
    debug::exit(EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}

#[exception]
unsafe fn HardFault(_frame: &ExceptionFrame) -> ! {
    debug::exit(EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}
