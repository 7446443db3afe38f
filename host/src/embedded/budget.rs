//! `sndt budget`: the exact memory of a `Map<V, B, C>` for capacities given at run time,
//! from the core's own size constants, and (given frames) the peak occupancy and
//! evictions of a trajectory at such a capacity, so a firmware author can pick `V` and `B`.
//!
//! ```
//! use sndt_host::embedded::budget::map_bytes;
//! // The firmware's map: 4096 surface voxels, 512 blocks, 40 classes.
//! assert_eq!(map_bytes(4096, 512, 40), sndt_core::Map::<4096, 512, 40>::BYTES);
//! ```

use crate::dataset::frame::{Frame, LabelSource};
use anyhow::{bail, Result};
use sndt_core::{
    Config, Map, Record, StreamWriter, BLOCK_BYTES, BLOCK_TABLE_BYTES, MAP_HEADER_BYTES,
    SNAPSHOT_BLOCK_BYTES, SNAPSHOT_HEADER_BYTES, STREAM_FRAME_BYTES,
};

/// Fixed bytes of a surface voxel before its `C`-byte class histogram (sums, count, key,
/// hash links and bucket head, vote sampling); the voxel is `round_up(VOXEL_FIXED_BYTES + C, 4)` bytes
/// (`Map::<V, B, C>::VOXEL_BYTES`; tests check the two agree).
pub const VOXEL_FIXED_BYTES: usize = 56;

/// Fixed bytes of a voxel record in a snapshot before its histogram
/// (`Map::<V, B, C>::SNAPSHOT_VOXEL_BYTES == SNAPSHOT_VOXEL_FIXED_BYTES + C`).
pub const SNAPSHOT_VOXEL_FIXED_BYTES: usize = 47;

/// Bytes of one surface voxel with `classes` classes (`Map::<V, B, classes>::VOXEL_BYTES`).
pub fn voxel_bytes(classes: usize) -> usize {
    (VOXEL_FIXED_BYTES + classes).div_ceil(4) * 4
}

/// Exact bytes of `Map<voxels, blocks, classes>` (`Map::BYTES`, its `size_of`):
/// `round_up(MAP_HEADER_BYTES + voxels * voxel_bytes(classes) + block_table_bytes(blocks), 8)`.
pub fn map_bytes(voxels: usize, blocks: usize, classes: usize) -> usize {
    (MAP_HEADER_BYTES + voxels * voxel_bytes(classes) + block_table_bytes(blocks)).div_ceil(8) * 8
}

/// Bytes of the block table (8-byte aligned):
/// `round_up(BLOCK_TABLE_BYTES + blocks * BLOCK_BYTES, 8)`.
pub fn block_table_bytes(blocks: usize) -> usize {
    (BLOCK_TABLE_BYTES + blocks * BLOCK_BYTES).div_ceil(8) * 8
}

/// Bytes of the largest snapshot of such a map (every voxel and block in use): the buffer
/// `Map::write_snapshot` needs at most.
pub fn max_snapshot_bytes(voxels: usize, blocks: usize, classes: usize) -> usize {
    SNAPSHOT_HEADER_BYTES
        + blocks * SNAPSHOT_BLOCK_BYTES
        + voxels * (SNAPSHOT_VOXEL_FIXED_BYTES + classes)
        + 4
}

/// The memory report `sndt budget` prints.
pub fn report(cell: f32, classes: usize, voxels: usize, blocks: usize) -> String {
    let vb = voxel_bytes(classes);
    let total = map_bytes(voxels, blocks, classes);
    let kib = |b: usize| b as f64 / 1024.0;
    let mut s = String::new();
    s += &format!("Map<{voxels}, {blocks}, {classes}> (cell {cell} m)\n");
    s += &format!(
        "  surface voxel    round_up({VOXEL_FIXED_BYTES} + {classes}, 4) = {vb} bytes x {voxels} = {} bytes\n",
        vb * voxels
    );
    s += &format!(
        "  occupancy block  BLOCK_BYTES = {BLOCK_BYTES} bytes x {blocks} = {} bytes ({:.2} bytes per voxel of 4x4x4)\n",
        BLOCK_BYTES * blocks,
        BLOCK_BYTES as f64 / 64.0
    );
    s += &format!("  header           MAP_HEADER_BYTES = {MAP_HEADER_BYTES} bytes\n");
    s += &format!(
        "  total            round_up({MAP_HEADER_BYTES} + {voxels} x {vb} + round_up({BLOCK_TABLE_BYTES} + {blocks} x {BLOCK_BYTES}, 8), 8) = {total} bytes ({:.1} KiB)\n",
        kib(total)
    );
    s += &format!(
        "  largest snapshot {} bytes ({:.1} KiB)\n",
        max_snapshot_bytes(voxels, blocks, classes),
        kib(max_snapshot_bytes(voxels, blocks, classes))
    );
    let (h, h3) = (cell as f64, (cell as f64).powi(3));
    s += &format!(
        "  covers           {:.0} m^2 of surface (one voxel per {:.0} cm cell), {:.0} m^3 of observed space ({} blocks of {:.2} m^3)\n",
        voxels as f64 * h * h,
        h * 100.0,
        blocks as f64 * 64.0 * h3,
        blocks,
        64.0 * h3
    );
    s
}

/// Capacities (voxels, blocks) compiled into `sndt budget` for simulating a trajectory;
/// a request is rounded up to the first that holds it.
pub const CAPACITIES: [(usize, usize); 5] = [
    (4096, 512),
    (16384, 2048),
    (65536, 8192),
    (262_144, 32_768),
    (1 << 20, 1 << 17),
];

/// The smallest compiled capacity with at least `voxels` voxels and `blocks` blocks.
///
/// ```
/// assert_eq!(sndt_host::embedded::budget::pick_capacity(5000, 100), Some((16384, 2048)));
/// assert_eq!(sndt_host::embedded::budget::pick_capacity(4096, 512), Some((4096, 512)));
/// ```
pub fn pick_capacity(voxels: usize, blocks: usize) -> Option<(usize, usize)> {
    CAPACITIES
        .iter()
        .copied()
        .find(|&(v, b)| v >= voxels && b >= blocks)
}

/// Peak occupancy and evictions of one trajectory at one capacity.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TrajectoryBudget {
    /// Frames integrated.
    pub frames: usize,
    /// Most surface voxels in the map after any frame.
    pub peak_voxels: usize,
    /// Most occupancy blocks in the map after any frame.
    pub peak_blocks: usize,
    /// Surface voxels evicted in total.
    pub evicted_voxels: u64,
    /// Occupancy blocks evicted in total.
    pub evicted_blocks: u64,
    /// Point and free-space updates dropped (nothing could be evicted).
    pub dropped: u64,
    /// Records of evicted voxels and blocks (what a co-processor would send the host).
    pub spilled_records: u64,
    /// Bytes of the framed record stream each frame (COBS frames with CRC, as
    /// `sndt_core::StreamWriter` writes them for a UART).
    pub spill_bytes: Vec<u64>,
}

impl TrajectoryBudget {
    /// Mean spill stream bytes per frame.
    pub fn mean_spill_bytes(&self) -> f64 {
        self.spill_bytes.iter().sum::<u64>() as f64 / self.spill_bytes.len().max(1) as f64
    }

    /// Largest spill stream bytes of one frame.
    pub fn max_spill_bytes(&self) -> u64 {
        self.spill_bytes.iter().copied().max().unwrap_or(0)
    }
}

fn simulate_with<const V: usize, const B: usize>(
    frames: &mut dyn Iterator<Item = Result<Frame>>,
    config: Config,
    stride: u32,
) -> Result<TrajectoryBudget> {
    let mut map: Box<Map<V, B, 40>> =
        crate::mapping::boxed_map(config).map_err(|e| anyhow::anyhow!("config: {e}"))?;
    let mut out = TrajectoryBudget::default();
    let mut buf = [0u8; STREAM_FRAME_BYTES];
    let (mut writer, _) =
        StreamWriter::start(map.as_ref(), &mut buf).map_err(|e| anyhow::anyhow!("{e}"))?;
    for frame in frames {
        let frame = frame?;
        let points = frame.camera_points(LabelSource::Gt, stride);
        let mut bytes = 0u64;
        let mut sink = |r: Record<'_>| {
            bytes += writer.record(r, &mut buf).unwrap_or(0) as u64;
            true
        };
        let report = map
            .integrate_spilling(&frame.pose, &points, &mut sink)
            .map_err(|e| anyhow::anyhow!("{}: integrate: {e}", frame.id))?;
        out.spilled_records += report.records_spilled as u64;
        out.spill_bytes.push(bytes);
        out.frames += 1;
        out.peak_voxels = out.peak_voxels.max(map.len());
        out.peak_blocks = out.peak_blocks.max(map.block_count());
    }
    let s = map.stats();
    out.evicted_voxels = s.voxels_evicted;
    out.evicted_blocks = s.blocks_evicted;
    out.dropped = s.dropped_points + s.dropped_misses;
    Ok(out)
}

/// Integrates `frames` (one trajectory, in order; ground-truth labels, every `stride`-th
/// pixel) into a fresh `Map<V, B, 40>` with `(V, B) = capacity`, one of [`CAPACITIES`], and
/// returns the peak occupancy and evictions.
///
/// ```
/// use sndt_host::embedded::budget::simulate;
/// let frames = sndt_host::embedded::budget::room_frames(2, 64, 48);
/// let b = simulate(frames.into_iter().map(Ok), sndt_core::Config::DEFAULT, (4096, 512), 1).unwrap();
/// assert_eq!(b.frames, 2);
/// assert!(b.peak_voxels > 0 && b.peak_voxels <= 4096);
/// ```
pub fn simulate(
    frames: impl IntoIterator<Item = Result<Frame>>,
    config: Config,
    capacity: (usize, usize),
    stride: u32,
) -> Result<TrajectoryBudget> {
    let it = &mut frames.into_iter();
    match capacity {
        (4096, 512) => simulate_with::<4096, 512>(it, config, stride),
        (16384, 2048) => simulate_with::<16384, 2048>(it, config, stride),
        (65536, 8192) => simulate_with::<65536, 8192>(it, config, stride),
        (262_144, 32_768) => simulate_with::<262_144, 32_768>(it, config, stride),
        (1_048_576, 131_072) => simulate_with::<1_048_576, 131_072>(it, config, stride),
        (v, b) => bail!("capacity ({v}, {b}) is not compiled in; use one of {CAPACITIES:?}"),
    }
}

/// Runs [`simulate`] on every trajectory of a dataset; returns `(trajectory, budget)`.
pub fn simulate_dataset(
    dataset: &dyn crate::dataset::source::Dataset,
    config: Config,
    capacity: (usize, usize),
    stride: u32,
) -> Result<Vec<(String, TrajectoryBudget)>> {
    dataset
        .trajectories()
        .into_iter()
        .map(|(name, ids)| {
            let frames = ids.iter().map(|id| dataset.load(id));
            Ok((name, simulate(frames, config, capacity, stride)?))
        })
        .collect()
}

/// One table row per trajectory (markdown), for `sndt budget DATASET`: the budgets at the
/// simulated `capacity`, and whether the peaks fit the `requested` (voxels, blocks).
pub fn table(
    rows: &[(String, TrajectoryBudget)],
    capacity: (usize, usize),
    requested: (usize, usize),
) -> String {
    let mut s = format!(
        "| trajectory | frames | peak voxels (of {}) | peak blocks (of {}) | evicted voxels | evicted blocks | dropped updates | fits {} / {} |\n|---|---|---|---|---|---|---|---|\n",
        capacity.0, capacity.1, requested.0, requested.1
    );
    for (name, b) in rows {
        let fits = b.peak_voxels <= requested.0
            && b.peak_blocks <= requested.1
            && b.evicted_voxels + b.evicted_blocks == 0;
        s += &format!(
            "| {name} | {} | {} | {} | {} | {} | {} | {} |\n",
            b.frames,
            b.peak_voxels,
            b.peak_blocks,
            b.evicted_voxels,
            b.evicted_blocks,
            b.dropped,
            if fits { "yes" } else { "no (evicts)" }
        );
    }
    s
}

/// The spill bandwidth of each trajectory: records and stream bytes per frame, and the
/// bytes per second at `fps` frames per second against a UART of `baud` (8N1: 10 bits per
/// byte).
///
/// ```
/// use sndt_host::embedded::budget::{spill_table, TrajectoryBudget};
/// let b = TrajectoryBudget { frames: 2, spill_bytes: vec![1000, 3000], ..Default::default() };
/// let t = spill_table(&[("room".into(), b)], 10.0, 921_600);
/// assert!(t.contains("| room | 0 | 2000 | 3000 | 20000 | 30000 | yes |"), "{t}");
/// ```
pub fn spill_table(rows: &[(String, TrajectoryBudget)], fps: f64, baud: u32) -> String {
    let link = baud as f64 / 10.0;
    let mut s = format!(
        "\nspill to the host (every evicted record, COBS-framed with CRC) at {fps} frames/s, \
         against a {baud}-baud UART ({link:.0} bytes/s):\n\n\
         | trajectory | records | bytes/frame mean | bytes/frame max | bytes/s mean | bytes/s max | fits the UART |\n\
         |---|---|---|---|---|---|---|\n"
    );
    for (name, b) in rows {
        let (mean, max) = (b.mean_spill_bytes() * fps, b.max_spill_bytes() as f64 * fps);
        let fits = if max <= link {
            "yes"
        } else if mean <= link {
            "on average (buffer the peaks)"
        } else {
            "no"
        };
        s += &format!(
            "| {name} | {} | {:.0} | {} | {mean:.0} | {max:.0} | {fits} |\n",
            b.spilled_records,
            b.mean_spill_bytes(),
            b.max_spill_bytes()
        );
    }
    s
}

/// `n` frames of the built-in box room (`room::orbit`) at `width x height`, as dataset
/// frames of one trajectory `room/cam_00` (for tests and examples).
pub fn room_frames(n: usize, width: u32, height: u32) -> Vec<Frame> {
    use crate::dataset::frame::{FrameId, Rays};
    let scene = crate::dataset::synthetic::room::Scene::simple_room();
    let s = width as f32 / crate::dataset::synthetic::room::HYPERSIM_CAMERA.width as f32;
    let cam = sndt_core::Pinhole {
        fx: crate::dataset::synthetic::room::HYPERSIM_CAMERA.fx * s,
        fy: crate::dataset::synthetic::room::HYPERSIM_CAMERA.fy * s,
        cx: width as f32 / 2.0,
        cy: height as f32 / 2.0,
        width,
        height,
    };
    let rays = std::sync::Arc::new(Rays::Pinhole(cam));
    crate::dataset::synthetic::room::orbit(n)
        .into_iter()
        .enumerate()
        .map(|(i, pose)| {
            let (depth, labels) = scene.render(&pose, &cam);
            Frame {
                id: FrameId {
                    scene: "room".into(),
                    cam: "cam_00".into(),
                    index: i as u32,
                },
                pose,
                rays: rays.clone(),
                depth,
                depth_kind: sndt_core::DepthKind::Planar,
                labels: Some(labels),
                predictions: None,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    macro_rules! check {
        ($(($v:expr, $b:expr, $c:expr)),* $(,)?) => {$(
            assert_eq!(voxel_bytes($c), Map::<$v, $b, $c>::VOXEL_BYTES, "voxel bytes, C = {}", $c);
            assert_eq!(map_bytes($v, $b, $c), Map::<$v, $b, $c>::BYTES, "Map<{}, {}, {}>", $v, $b, $c);
            assert_eq!(map_bytes($v, $b, $c), core::mem::size_of::<Map<$v, $b, $c>>());
            assert_eq!(SNAPSHOT_VOXEL_FIXED_BYTES + $c, Map::<$v, $b, $c>::SNAPSHOT_VOXEL_BYTES);
        )*};
    }

    #[test]
    fn runtime_formula_equals_the_core_constants() {
        check!(
            (1, 1, 1),
            (1, 1, 2),
            (3, 1, 3),
            (7, 5, 4),
            (16, 4, 5),
            (100, 13, 13),
            (4096, 512, 40),
            (4096, 1024, 40),
            (33, 7, 41),
            (17, 3, 42),
            (9, 9, 43),
            (1000, 100, 100),
            (5, 2, 254),
        );
    }

    #[test]
    fn capacity_steps_and_report() {
        assert_eq!(pick_capacity(1, 1), Some((4096, 512)));
        assert_eq!(pick_capacity(4097, 1), Some((16384, 2048)));
        assert_eq!(pick_capacity(1, 9000), Some((262_144, 32_768)));
        assert_eq!(pick_capacity((1 << 20) + 1, 1), None);
        let r = report(0.1, 40, 4096, 512);
        assert!(r.contains("= 485512 bytes"), "{r}");
    }

    #[test]
    fn evictions_appear_when_the_capacity_is_too_small() {
        let frames = room_frames(6, 128, 96);
        let big = simulate(
            frames.clone().into_iter().map(Ok),
            Config::DEFAULT,
            (65536, 8192),
            1,
        )
        .unwrap();
        assert_eq!((big.evicted_voxels, big.evicted_blocks), (0, 0));
        assert!(big.peak_voxels > 4096, "{big:?}");
        let small = simulate(frames.into_iter().map(Ok), Config::DEFAULT, (4096, 512), 1).unwrap();
        assert_eq!(small.frames, 6);
        assert!(
            small.peak_voxels <= 4096 && small.evicted_voxels > 0,
            "{small:?}"
        );
    }
}
