//! The C types of the API (`repr(C)`, mirrored in `include/sndt.h`) and their conversion
//! to and from `sndt_core` types. Nothing here is `unsafe`.

use sndt_core::{
    pose_from_matrix, validate_pose, Config, Error, FrameReport, Isometry3, Labels, MapStats,
    Matrix3, MissModel, Pinhole, Quaternion, Translation3, UnitQuaternion, Vector3,
};

/// What every function returns: `SNDT_OK` (0) or an error; `sndt_status_str` gives a message.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(non_camel_case_types)]
pub enum sndt_status {
    /// Success.
    SNDT_OK = 0,
    /// A required pointer is NULL.
    SNDT_ERR_NULL = 1,
    /// An argument is out of range or inconsistent: NaN or infinite values, a pose whose
    /// rotation is not one, a bad camera, image sizes that disagree, a misaligned pointer,
    /// an output buffer that overlaps another buffer of the call or the map.
    SNDT_ERR_BAD_ARG = 2,
    /// A configuration field is out of its documented range (which one is not reported
    /// here: the ranges are those of `sndt_config`).
    SNDT_ERR_CONFIG = 3,
    /// The storage is smaller than `SNDT_MAP_BYTES`, or a frame has more points than the
    /// core takes in one frame, or a snapshot holds more than this map's capacity.
    SNDT_ERR_CAPACITY = 4,
    /// An output buffer is too small (nothing was written).
    SNDT_ERR_BUFFER_TOO_SMALL = 5,
    /// The map pointer does not point at storage initialised by `sndt_map_init`.
    SNDT_ERR_NOT_INITIALISED = 6,
    /// The sensor (or a queried point) is outside the key range: +-32767 cells from the origin.
    SNDT_ERR_OUT_OF_RANGE = 7,
    /// A snapshot is truncated, not a snapshot, or fails its CRC or its invariants.
    SNDT_ERR_CORRUPT = 8,
    /// A snapshot of another format version or class count.
    SNDT_ERR_INCOMPATIBLE = 9,
}

use sndt_status::*;

impl From<Error> for sndt_status {
    fn from(e: Error) -> Self {
        match e {
            Error::InvalidConfig(_) => SNDT_ERR_CONFIG,
            Error::InvalidPose | Error::InvalidImage => SNDT_ERR_BAD_ARG,
            Error::PoseOutOfRange => SNDT_ERR_OUT_OF_RANGE,
            Error::FrameTooLarge | Error::SnapshotCapacity | Error::MapFull => SNDT_ERR_CAPACITY,
            Error::BufferTooSmall => SNDT_ERR_BUFFER_TOO_SMALL,
            Error::SnapshotTruncated
            | Error::SnapshotMagic
            | Error::SnapshotChecksum
            | Error::SnapshotCorrupt
            | Error::RecordCorrupt
            | Error::StreamChecksum
            | Error::StreamOrder
            | Error::StreamTruncated => SNDT_ERR_CORRUPT,
            Error::SnapshotVersion | Error::SnapshotClasses | Error::ConfigMismatch => {
                SNDT_ERR_INCOMPATIBLE
            }
        }
    }
}

/// The map's configuration: every field of the core's `Config` (see its documentation for
/// ranges). Start from `sndt_config_default()`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[allow(non_camel_case_types)]
pub struct sndt_config {
    /// Voxel edge in metres, [0.001, 100]. Default 0.10.
    pub cell_size: f32,
    /// Offsets are quantised to cell / 2^quant_bits. Default 6.
    pub quant_bits: u8,
    /// Points before a voxel's Gaussian is valid. Default 3.
    pub n_min: u32,
    /// Eigenvalue floor ratio. Default 1e-3.
    pub eigen_ratio: f32,
    /// Point cap per voxel. Default 2048.
    pub n_max: u32,
    /// Log-odds of a hit. Default 0.85.
    pub hit: f32,
    /// Log-odds of a constant miss. Default -0.4.
    pub miss: f32,
    /// Lower log-odds clamp. Default -2.0.
    pub clamp_min: f32,
    /// Upper log-odds clamp. Default 3.5.
    pub clamp_max: f32,
    /// NDT-OM miss weight. Default 0.1.
    pub lambda: f32,
    /// Log-odds of the see-through miss that clears what moved: [-30, 0], a multiple of
    /// 1/1024. Default -3. 0 is S-NDT as published.
    pub see_through_miss: f32,
    /// Range noise sigma = noise_base + noise_quadratic * r^2, metres. Default 0.02.
    pub noise_base: f32,
    /// Default 0.0025.
    pub noise_quadratic: f32,
    /// Points farther than this (metres) only clear free space up to it. Default 20,
    /// [0.001, 1e4], and at most 4096 cells: max_range <= 4096 * cell_size.
    pub max_range: f32,
    /// Labels per point that vote (1..=3). Default 1.
    pub top_k: u8,
    /// Labels scored below this (0..=255) do not vote. Default 0.
    pub min_score: u8,
    /// About how many votes a voxel takes per frame (1..=64). Default 64.
    pub votes_per_frame: u8,
    /// Free-space model: 0 NDT-OM (default), 1 constant miss.
    pub miss_model: u8,
    /// Gaussian radius (Mahalanobis) that rays and renders hit. Default 2.5.
    pub render_radius: f32,
}

impl sndt_config {
    /// The core's `Config::DEFAULT`.
    pub const DEFAULT: sndt_config = sndt_config::from_core(&Config::DEFAULT);

    /// The C mirror of a core config.
    pub const fn from_core(c: &Config) -> Self {
        sndt_config {
            cell_size: c.cell_size,
            quant_bits: c.quant_bits,
            n_min: c.n_min,
            eigen_ratio: c.eigen_ratio,
            n_max: c.n_max,
            hit: c.hit,
            miss: c.miss,
            clamp_min: c.clamp_min,
            clamp_max: c.clamp_max,
            lambda: c.lambda,
            noise_base: c.noise_base,
            noise_quadratic: c.noise_quadratic,
            max_range: c.max_range,
            top_k: c.top_k,
            min_score: c.min_score,
            votes_per_frame: c.votes_per_frame,
            miss_model: c.miss_model as u8,
            render_radius: c.render_radius,
            see_through_miss: c.see_through_miss,
        }
    }

    /// The core config, checked (`SNDT_ERR_CONFIG` when a field is out of range).
    pub fn to_core(&self) -> Result<Config, sndt_status> {
        let miss_model = match self.miss_model {
            0 => MissModel::NdtOm,
            1 => MissModel::Constant,
            _ => return Err(SNDT_ERR_CONFIG),
        };
        let c = Config {
            cell_size: self.cell_size,
            quant_bits: self.quant_bits,
            n_min: self.n_min,
            eigen_ratio: self.eigen_ratio,
            n_max: self.n_max,
            hit: self.hit,
            miss: self.miss,
            clamp_min: self.clamp_min,
            clamp_max: self.clamp_max,
            lambda: self.lambda,
            noise_base: self.noise_base,
            noise_quadratic: self.noise_quadratic,
            max_range: self.max_range,
            top_k: self.top_k,
            min_score: self.min_score,
            votes_per_frame: self.votes_per_frame,
            miss_model,
            render_radius: self.render_radius,
            see_through_miss: self.see_through_miss,
        };
        c.validate().map_err(|_| SNDT_ERR_CONFIG)?;
        Ok(c)
    }
}

/// Camera-to-world (sensor-to-world) pose: a unit quaternion (w, x, y, z) and a
/// translation in metres, the sensor's position. Build it with
/// `sndt_pose_from_matrix4` or `sndt_pose_from_quaternion`, which check it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[allow(non_camel_case_types)]
pub struct sndt_pose {
    /// Rotation as a unit quaternion: w, x, y, z.
    pub q: [f32; 4],
    /// Translation, metres.
    pub t: [f32; 3],
}

impl sndt_pose {
    /// The pose of a core isometry.
    pub fn from_isometry(p: &Isometry3<f32>) -> Self {
        let q = p.rotation.quaternion();
        let t = p.translation.vector;
        sndt_pose {
            q: [q.w, q.i, q.j, q.k],
            t: [t.x, t.y, t.z],
        }
    }

    /// The core isometry, checked as the core checks every pose (`SNDT_ERR_BAD_ARG`).
    pub fn to_isometry(&self) -> Result<Isometry3<f32>, sndt_status> {
        let [w, x, y, z] = self.q;
        let rotation = UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z));
        let [tx, ty, tz] = self.t;
        let pose = Isometry3::from_parts(Translation3::new(tx, ty, tz), rotation);
        validate_pose(&pose).map_err(sndt_status::from)?;
        Ok(pose)
    }

    /// From a row-major 4x4 camera-to-world matrix whose last row is 0 0 0 1.
    pub fn from_matrix4(m: &[f32; 16]) -> Result<Self, sndt_status> {
        if m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0 {
            return Err(SNDT_ERR_BAD_ARG);
        }
        let r = Matrix3::new(m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]);
        let t = Vector3::new(m[3], m[7], m[11]);
        let pose = pose_from_matrix(&r, &t).map_err(sndt_status::from)?;
        Ok(sndt_pose::from_isometry(&pose))
    }
}

/// Pinhole intrinsics in pixels (OpenCV axes: x right, y down, z forward; pixel (col, row)
/// has its centre at (col + 0.5, row + 0.5)).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[allow(non_camel_case_types)]
pub struct sndt_pinhole {
    /// Focal length x, pixels.
    pub fx: f32,
    /// Focal length y, pixels.
    pub fy: f32,
    /// Principal point x, pixels.
    pub cx: f32,
    /// Principal point y, pixels.
    pub cy: f32,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
}

impl sndt_pinhole {
    /// The core camera.
    pub fn to_core(self) -> Pinhole {
        Pinhole {
            fx: self.fx,
            fy: self.fy,
            cx: self.cx,
            cy: self.cy,
            width: self.width,
            height: self.height,
        }
    }
}

/// Top-k labels of a point or pixel: class ids (1..=SNDT_CLASSES, 0 = void) best first,
/// their scores (0..=255), and how many are used (0..=3). The same 7 bytes as the core's
/// `Labels`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(non_camel_case_types)]
pub struct sndt_labels {
    /// Class ids, best first.
    pub classes: [u8; 3],
    /// Scores, best first.
    pub scores: [u8; 3],
    /// Entries used, 0..=3.
    pub len: u8,
}

const _: () = {
    assert!(core::mem::size_of::<sndt_labels>() == core::mem::size_of::<Labels>());
    assert!(core::mem::align_of::<sndt_labels>() == core::mem::align_of::<Labels>());
};

impl sndt_labels {
    /// The core labels.
    pub fn to_core(self) -> Labels {
        Labels {
            classes: self.classes,
            scores: self.scores,
            len: self.len,
        }
    }
}

/// One point in the sensor frame (metres) with its labels.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[allow(non_camel_case_types)]
pub struct sndt_point {
    /// x, y, z in the sensor frame, metres.
    pub xyz: [f32; 3],
    /// Labels of the point.
    pub labels: sndt_labels,
}

/// What integrating one frame did (the core's `FrameReport`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[allow(non_camel_case_types)]
pub struct sndt_frame_report {
    /// Points that updated the map.
    pub points_used: u32,
    /// Points beyond max_range (they only clear free space up to it).
    pub truncated: u32,
    /// Pixels or points without a valid depth (0, negative, NaN, inf).
    pub rejected_depth: u32,
    /// Points with a class id above SNDT_CLASSES.
    pub rejected_label: u32,
    /// Points outside the key range.
    pub rejected_out_of_range: u32,
    /// Point updates dropped because the map was full and nothing could be evicted.
    pub dropped_points: u32,
    /// Free-space updates dropped for the same reason.
    pub dropped_misses: u32,
    /// Distinct voxels the frame's points ended in.
    pub end_voxels: u32,
    /// Free-space rays cast.
    pub rays: u32,
    /// Surface voxels created.
    pub voxels_created: u32,
    /// Occupancy blocks created.
    pub blocks_created: u32,
    /// Surface voxels evicted to make room.
    pub voxels_evicted: u32,
    /// Occupancy blocks evicted to make room.
    pub blocks_evicted: u32,
    /// Records of evicted voxels and blocks handed to a record sink. Always 0 here: this
    /// API integrates without a sink (evictions are counted in voxels_evicted and
    /// blocks_evicted only).
    pub records_spilled: u32,
    /// Records of evicted voxels and blocks a record sink refused (lost). Always 0 here, as
    /// records_spilled.
    pub records_dropped: u32,
}

impl From<FrameReport> for sndt_frame_report {
    fn from(r: FrameReport) -> Self {
        sndt_frame_report {
            points_used: r.points_used,
            truncated: r.truncated,
            rejected_depth: r.rejected_depth,
            rejected_label: r.rejected_label,
            rejected_out_of_range: r.rejected_out_of_range,
            dropped_points: r.dropped_points,
            dropped_misses: r.dropped_misses,
            end_voxels: r.end_voxels,
            rays: r.rays,
            voxels_created: r.voxels_created,
            blocks_created: r.blocks_created,
            voxels_evicted: r.voxels_evicted,
            blocks_evicted: r.blocks_evicted,
            records_spilled: r.records_spilled,
            records_dropped: r.records_dropped,
        }
    }
}

/// Occupancy of a voxel: 0 unknown (never observed), 1 free, 2 occupied.
pub type sndt_occupancy = u8;

/// What the map knows at one point.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[allow(non_camel_case_types)]
pub struct sndt_query {
    /// 0 unknown, 1 free, 2 occupied.
    pub occupancy: sndt_occupancy,
    /// Occupancy probability from the voxel's log-odds (0.5 when unknown).
    pub probability: f32,
    /// Most voted class (1..=SNDT_CLASSES), 0 when the voxel has no votes.
    pub class_id: u8,
    /// That class's share of the voxel's votes, 0..=1.
    pub class_confidence: f32,
    /// Points in the voxel's Gaussian (0 when it has none).
    pub points: u32,
}

/// The first Gaussian a ray enters.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[allow(non_camel_case_types)]
pub struct sndt_ray_hit {
    /// 1 when the ray hit, 0 otherwise (the other fields are then 0).
    pub hit: u8,
    /// Distance from the origin along the ray, metres.
    pub t: f32,
    /// The voxel's class, 0 when it has no votes.
    pub class_id: u8,
}

/// The map's memory and totals.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[allow(non_camel_case_types)]
pub struct sndt_stats {
    /// Bytes of the map's storage (SNDT_MAP_BYTES).
    pub map_bytes: u64,
    /// Surface voxels in use, and the capacity SNDT_VOXELS.
    pub voxels: u32,
    /// SNDT_VOXELS.
    pub voxel_capacity: u32,
    /// Occupancy blocks in use.
    pub blocks: u32,
    /// SNDT_BLOCKS.
    pub block_capacity: u32,
    /// SNDT_CLASSES.
    pub classes: u32,
    /// Frames integrated.
    pub frames: u32,
    /// Surface voxels evicted to make room, in total.
    pub voxels_evicted: u64,
    /// Occupancy blocks evicted, in total.
    pub blocks_evicted: u64,
    /// Point updates dropped (map full), in total.
    pub dropped_points: u64,
    /// Free-space updates dropped (map full), in total.
    pub dropped_misses: u64,
    /// Bytes `sndt_save` writes now.
    pub snapshot_bytes: u64,
}

impl sndt_stats {
    /// Totals of a core map's stats and counts.
    pub fn new(s: &MapStats, counts: [usize; 5], map_bytes: usize, snapshot: usize) -> Self {
        let [voxels, voxel_capacity, blocks, block_capacity, classes] = counts.map(|c| c as u32);
        sndt_stats {
            map_bytes: map_bytes as u64,
            voxels,
            voxel_capacity,
            blocks,
            block_capacity,
            classes,
            frames: s.frames,
            voxels_evicted: s.voxels_evicted,
            blocks_evicted: s.blocks_evicted,
            dropped_points: s.dropped_points,
            dropped_misses: s.dropped_misses,
            snapshot_bytes: snapshot as u64,
        }
    }
}
