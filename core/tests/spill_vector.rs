//! The spill run of the cross-architecture test vector: the committed frames
//! (`targets/cortex-m4f/vector/frames.bin`) integrated into the firmware's
//! `Map<4096, 512, 40>` at a cell size small enough that it overflows, every evicted voxel
//! and block merged into a larger global map, then the device's last map merged too. The
//! global map's CRC must equal `expected_spill_crc.txt`, which `sndt testvector --spill`
//! (x86-64) wrote and the Cortex-M4F firmware (QEMU, through its UART record stream)
//! reproduces; `scripts/aarch64.sh` runs this test under qemu-aarch64. The run is the
//! host's `embedded::spill::own_run`, repeated here with the core alone.

use sndt_core::{
    pose_from_matrix, Config, Depth, DepthImage, DepthKind, Isometry3, LabelImage, Map, Matrix3,
    Pinhole, Record, Vector3,
};

const VECTOR: &[u8] = include_bytes!("../../targets/cortex-m4f/vector/frames.bin");
const EXPECTED: &str = include_str!("../../targets/cortex-m4f/vector/expected_spill_crc.txt");

/// The spill run's cell size (metres), as `sndt testvector --spill` and the firmware.
const SPILL_CELL: f32 = 0.09;

/// The firmware's map, and the global map its records merge into.
type Device = Map<4096, 512, 40>;
type Global = Map<{ 1 << 16 }, { 1 << 14 }, 40>;

/// Little-endian `u16`, `u32` and `f32` at byte `o` of the vector.
fn u16_at(o: usize) -> u16 {
    u16::from_le_bytes([VECTOR[o], VECTOR[o + 1]])
}
fn u32_at(o: usize) -> u32 {
    u32::from_le_bytes(VECTOR[o..o + 4].try_into().unwrap())
}
fn f32_at(o: usize) -> f32 {
    f32::from_bits(u32_at(o))
}

/// One frame of the vector: camera-to-world pose, planar depths (metres), labels.
type Frame = (Isometry3<f32>, Vec<f32>, Vec<u8>);

/// The vector's frames: pose, planar depths and labels (format: host/src/embedded/testvector.rs:
/// a 56-byte header, 8-byte probes, then per frame 12 f32 of pose, W H f32 depths, W H labels).
fn frames() -> (Pinhole, Vec<Frame>) {
    assert_eq!(&VECTOR[..8], b"SNDTVEC\0");
    let (frames, probes) = (u16_at(10) as usize, u16_at(12) as usize);
    let camera = Pinhole {
        width: u32_at(24),
        height: u32_at(28),
        fx: f32_at(32),
        fy: f32_at(36),
        cx: f32_at(40),
        cy: f32_at(44),
    };
    let n = (camera.width * camera.height) as usize;
    let mut o = 56 + 8 * probes;
    let mut out = Vec::new();
    for _ in 0..frames {
        let m: [f32; 12] = std::array::from_fn(|i| f32_at(o + 4 * i));
        let rot = Matrix3::new(m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8]);
        let pose = pose_from_matrix(&rot, &Vector3::new(m[9], m[10], m[11])).unwrap();
        let depth = (0..n).map(|i| f32_at(o + 48 + 4 * i)).collect();
        let labels = VECTOR[o + 48 + 4 * n..o + 48 + 5 * n].to_vec();
        out.push((pose, depth, labels));
        o += 48 + 5 * n;
    }
    assert_eq!(o, VECTOR.len());
    (camera, out)
}

/// The spill run: returns the global map's CRC, the records spilled and the evictions.
fn spill_run() -> (u32, u32, u64, u64) {
    let config = Config::with_cell_size(SPILL_CELL);
    let mut device: Box<Device> = Box::new(Map::new(config));
    let mut global: Box<Global> = Box::new(Map::new(config));
    let (camera, frames) = frames();
    let mut spilled = 0;
    for (pose, depth, labels) in &frames {
        let image = DepthImage {
            camera,
            depth: Depth::Metres(depth),
            kind: DepthKind::Planar,
            labels: LabelImage::Top1(labels),
            stride: 1,
        };
        let mut sink = |r: Record<'_>| global.merge_record(r).is_ok();
        let report = device
            .integrate_depth_spilling(pose, &image, &mut sink)
            .unwrap();
        assert_eq!(report.records_dropped, 0, "the global map refused a record");
        spilled += report.records_spilled;
    }
    global.merge(&device).unwrap();
    let stats = device.stats();
    (
        global.checksum(),
        spilled,
        stats.voxels_evicted,
        stats.blocks_evicted,
    )
}

#[test]
fn spill_run_matches_the_committed_crc() {
    // The maps are large (the global one 10 MB): build them on a thread with room for them.
    let stack = 4 * (std::mem::size_of::<Global>() + std::mem::size_of::<Device>()) + (16 << 20);
    let (crc, spilled, voxels, blocks) = std::thread::Builder::new()
        .stack_size(stack)
        .spawn(spill_run)
        .unwrap()
        .join()
        .unwrap();
    println!("spill crc {crc:#010x}: {spilled} records, evicted {voxels} voxels, {blocks} blocks");
    assert!(
        voxels > 1000 && blocks > 100,
        "the device map did not overflow"
    );
    let expected = u32::from_str_radix(EXPECTED.trim().trim_start_matches("0x"), 16).unwrap();
    assert_eq!(
        crc, expected,
        "spill CRC differs from expected_spill_crc.txt"
    );
}
