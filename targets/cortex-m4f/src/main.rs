//! Firmware smoke test: integrates a synthetic scene (wall, door, floor seen from 4 poses)
//! into a `Map<4096, 512, 40>` on a Cortex-M4F, ray casts it, checks the hits and prints
//! the map's counts and CRC over defmt (semihosting). Exit status 0 only if all checks pass.
#![no_std]
#![no_main]

use core::cell::RefCell;

use cortex_m::interrupt::{self, Mutex};
use cortex_m_rt::{entry, exception, ExceptionFrame};
use cortex_m_semihosting::debug::{self, EXIT_FAILURE, EXIT_SUCCESS};
use defmt_semihosting as _;
use sndt_core::{
    pose_from_matrix, Config, DepthImage, DepthKind, LabelImage, Map, Matrix3, Pinhole, Point3,
    Vector3,
};

type FwMap = Map<4096, 512, 40>;

/// The whole map lives in one static (no heap, no `static mut`).
static MAP: Mutex<RefCell<FwMap>> = Mutex::new(RefCell::new(FwMap::new(Config::DEFAULT)));

// ---------------------------------------------------------------------------------------
// Synthetic scene, computed analytically at compile time (the images live in flash).
// World: z up. Wall plane x = WALL_X (class WALL, with a DOOR region), floor z = 0 (FLOOR).
// ---------------------------------------------------------------------------------------

const W: usize = 160;
const H: usize = 120;
const N: usize = W * H;
const CAM: Pinhole = Pinhole {
    fx: 120.0,
    fy: 120.0,
    cx: 80.0,
    cy: 60.0,
    width: W as u32,
    height: H as u32,
};

const WALL_X: f32 = 3.0;
const WALL: u8 = 1; // NYU40 "wall"
const FLOOR: u8 = 2; // NYU40 "floor"
const DOOR: u8 = 8; // NYU40 "door"
const DOOR_Y: (f32, f32) = (0.6, 1.4);
const DOOR_Z: f32 = 2.0;

/// A camera pose: yaw (cos, sin) about world z and the optical centre; the camera looks
/// horizontally (OpenCV axes: x right, y down, z forward).
struct PoseDef {
    c: f32,
    s: f32,
    t: [f32; 3],
}

const POSES: [PoseDef; 4] = [
    PoseDef {
        c: 1.0,
        s: 0.0,
        t: [0.0, 0.0, 1.2],
    },
    PoseDef {
        c: 0.988_771_1,
        s: 0.149_438_13,
        t: [0.3, -0.2, 1.2],
    }, // yaw +0.15 rad
    PoseDef {
        c: 0.988_771_1,
        s: -0.149_438_13,
        t: [0.3, 0.2, 1.2],
    }, // yaw -0.15 rad
    PoseDef {
        c: 0.998_750_26,
        s: 0.049_979_17,
        t: [0.6, 0.0, 1.0],
    }, // yaw +0.05 rad
];

impl PoseDef {
    /// Camera-to-world rotation, row-major.
    const fn rot(&self) -> [[f32; 3]; 3] {
        [
            [self.s, 0.0, self.c],
            [-self.c, 0.0, self.s],
            [0.0, -1.0, 0.0],
        ]
    }
}

/// Planar depth (0 = no hit) and class of pixel `(col, row)` seen from pose `p`.
const fn pixel(p: &PoseDef, col: usize, row: usize) -> (f32, u8) {
    let rx = (col as f32 + 0.5 - CAM.cx) / CAM.fx;
    let ry = (row as f32 + 0.5 - CAM.cy) / CAM.fy;
    let r = p.rot();
    let d = [
        r[0][0] * rx + r[0][1] * ry + r[0][2],
        r[1][0] * rx + r[1][1] * ry + r[1][2],
        r[2][0] * rx + r[2][1] * ry + r[2][2],
    ];
    // The camera ray has unit z, so the ray parameter is the planar depth.
    let mut depth = 0.0f32;
    let mut class = 0u8;
    if d[0] > 1e-6 {
        let t = (WALL_X - p.t[0]) / d[0];
        let (y, z) = (p.t[1] + t * d[1], p.t[2] + t * d[2]);
        if t > 0.0 && z >= 0.0 {
            depth = t;
            class = if y >= DOOR_Y.0 && y <= DOOR_Y.1 && z <= DOOR_Z {
                DOOR
            } else {
                WALL
            };
        }
    }
    if d[2] < -1e-6 {
        let t = -p.t[2] / d[2];
        if t > 0.0 && (depth == 0.0 || t < depth) {
            depth = t;
            class = FLOOR;
        }
    }
    (depth, class)
}

const fn depth_image(p: &PoseDef) -> [f32; N] {
    let mut out = [0.0f32; N];
    let mut i = 0;
    while i < N {
        out[i] = pixel(p, i % W, i / W).0;
        i += 1;
    }
    out
}

const fn label_image(p: &PoseDef) -> [u8; N] {
    let mut out = [0u8; N];
    let mut i = 0;
    while i < N {
        out[i] = pixel(p, i % W, i / W).1;
        i += 1;
    }
    out
}

static DEPTH: [[f32; N]; 4] = [
    depth_image(&POSES[0]),
    depth_image(&POSES[1]),
    depth_image(&POSES[2]),
    depth_image(&POSES[3]),
];
static LABELS: [[u8; N]; 4] = [
    label_image(&POSES[0]),
    label_image(&POSES[1]),
    label_image(&POSES[2]),
    label_image(&POSES[3]),
];

/// A ray cast check: origin, direction (world), expected distance and class.
struct Probe {
    origin: [f32; 3],
    dir: [f32; 3],
    t: f32,
    class: u8,
}

const PROBES: [Probe; 4] = [
    // Straight at the wall from pose 0.
    Probe {
        origin: [0.0, 0.0, 1.2],
        dir: [1.0, 0.0, 0.0],
        t: WALL_X,
        class: WALL,
    },
    // At the door region.
    Probe {
        origin: [0.0, 1.0, 1.2],
        dir: [1.0, 0.0, 0.0],
        t: WALL_X,
        class: DOOR,
    },
    // Wall to the right, from pose 3.
    Probe {
        origin: [0.6, -1.0, 1.0],
        dir: [1.0, 0.0, 0.0],
        t: WALL_X - 0.6,
        class: WALL,
    },
    // Down to the floor at x = 2.7: |(2.7, 0, -1.2)| = 2.954657.
    Probe {
        origin: [0.0, 0.0, 1.2],
        dir: [2.7, 0.0, -1.2],
        t: 2.954_657,
        class: FLOOR,
    },
];
const T_TOL: f32 = 0.15;

#[entry]
fn main() -> ! {
    let ok = interrupt::free(|cs| run(&mut MAP.borrow(cs).borrow_mut()));
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

fn run(map: &mut FwMap) -> bool {
    let mut ok = true;
    defmt::println!(
        "map: Map<4096, 512, 40> = {=usize} bytes ({=usize} per voxel)",
        FwMap::BYTES,
        FwMap::VOXEL_BYTES
    );
    for (k, p) in POSES.iter().enumerate() {
        let r = p.rot();
        let rot = Matrix3::new(
            r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
        );
        let pose = match pose_from_matrix(&rot, &Vector3::new(p.t[0], p.t[1], p.t[2])) {
            Ok(pose) => pose,
            Err(_) => {
                defmt::error!("frame {=usize}: invalid pose", k);
                return false;
            }
        };
        let image = DepthImage {
            camera: CAM,
            depth: &DEPTH[k],
            kind: DepthKind::Planar,
            labels: LabelImage::Top1(&LABELS[k]),
            stride: 1,
        };
        match map.integrate_depth(&pose, &image) {
            Ok(rep) => {
                defmt::println!(
                    "frame {=usize}: points {=u32}, end voxels {=u32}, rays {=u32}, voxels +{=u32} -{=u32}, blocks +{=u32} -{=u32}, dropped {=u32}/{=u32}",
                    k,
                    rep.points_used,
                    rep.end_voxels,
                    rep.rays,
                    rep.voxels_created,
                    rep.voxels_evicted,
                    rep.blocks_created,
                    rep.blocks_evicted,
                    rep.dropped_points,
                    rep.dropped_misses
                );
                if rep.points_used as usize != N || rep.rejected_label != 0 {
                    defmt::error!("frame {=usize}: not every pixel was used", k);
                    ok = false;
                }
            }
            Err(_) => {
                defmt::error!("frame {=usize}: integrate_depth failed", k);
                ok = false;
            }
        }
    }

    for (i, pr) in PROBES.iter().enumerate() {
        let dir = Vector3::new(pr.dir[0], pr.dir[1], pr.dir[2]).normalize();
        let origin = Point3::new(pr.origin[0], pr.origin[1], pr.origin[2]);
        match map.raycast(&origin, &dir, 10.0) {
            Some(hit) => {
                let good = (hit.t - pr.t).abs() < T_TOL && hit.class == pr.class;
                defmt::println!(
                    "probe {=usize}: t = {=f32} (expected {=f32}), class {=u8} (expected {=u8}) {=str}",
                    i,
                    hit.t,
                    pr.t,
                    hit.class,
                    pr.class,
                    if good { "ok" } else { "WRONG" }
                );
                ok &= good;
            }
            None => {
                defmt::error!("probe {=usize}: no hit", i);
                ok = false;
            }
        }
    }

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
    defmt::println!("checksum (CRC-32) {=u32:#010x}", map.checksum());
    ok &= voxels > 0 && stats.frames == POSES.len() as u32;
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
