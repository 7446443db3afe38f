//! Writing ROS 2 recordings: rosbag2 bags as `ros2 bag record` writes them on Humble (MCAP
//! with the `ros2` profile, CDR messages, `ros2msg` schemas, the recorded QoS per topic),
//! as one `.mcap` file or as a bag folder, and a synthetic trajectory as such a bag.

use crate::atomic::{commit, temporary, write_bytes};
use crate::dataset::frame::{Frame, Rays};
use crate::dataset::prepared::{depth_to_mm, Extrinsics};
use crate::dataset::ros::metadata::{
    serialize_qos, BagInfo, MetadataFile, OfferedQos, QosProfile, TopicMetadata,
    TopicWithMessageCount, METADATA_FILE, ROS_DISTRO,
};
use crate::dataset::ros::msgs::{
    self, CameraInfo, Header, Image, TfMessage, Time, Transform, TransformStamped,
};
use anyhow::{anyhow, bail, Context, Result};
use serde::Serialize;
use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// A rosbag2 bag being written: an MCAP file of ROS 2 messages, or with a folder path (one
/// ending in `/`, or an existing directory) a bag folder `DIR/<DIR's name>_0.mcap` plus
/// `DIR/metadata.yaml`, which is what `ros2 bag record -s mcap` leaves. The MCAP file is
/// written into a temporary file that [`BagWriter::finish`] syncs and renames over the
/// target (a crash never leaves a truncated bag in its place), and `metadata.yaml` only
/// after it.
pub struct BagWriter {
    writer: mcap::Writer<BufWriter<File>>,
    /// Topic name -> (channel id, index into `topics`).
    channels: HashMap<String, (u16, usize)>,
    /// The declared topics with their message counts, in declaration order.
    topics: Vec<TopicWithMessageCount>,
    /// First and last log time written, ns.
    span: Option<(u64, u64)>,
    sequence: u32,
    tmp: PathBuf,
    path: PathBuf,
    /// The bag folder, when writing one.
    folder: Option<PathBuf>,
}

/// Whether `path` names a bag folder rather than an `.mcap` file: it ends in a path
/// separator or is an existing directory.
///
/// ```
/// use sndt_host::output::ros::write::is_folder;
/// use std::path::Path;
/// assert!(is_folder(Path::new("out/robot/")));
/// assert!(!is_folder(Path::new("out/robot.mcap")));
/// ```
pub fn is_folder(path: &Path) -> bool {
    let text = path.as_os_str().to_string_lossy();
    text.ends_with('/') || text.ends_with(std::path::MAIN_SEPARATOR) || path.is_dir()
}

/// The bag of one of several trajectories: `<stem>_<name>.mcap` beside an `.mcap` path, or
/// the folder `<dir>_<name>/` beside a folder path (so each trajectory is a bag of the same
/// form). `fallback` is the stem for a path without one.
///
/// ```
/// use sndt_host::output::ros::write::sibling_bag;
/// use std::path::Path;
/// let file = sibling_bag(Path::new("out/map.mcap"), "synth_00/cam_00", "map");
/// assert_eq!(file, Path::new("out/map_synth_00_cam_00.mcap"));
/// let folder = sibling_bag(Path::new("out/bags/"), "synth_00/cam_00", "map");
/// assert_eq!(folder, Path::new("out/bags_synth_00_cam_00/"));
/// assert!(sndt_host::output::ros::write::is_folder(&folder));
/// ```
pub fn sibling_bag(path: &Path, name: &str, fallback: &str) -> PathBuf {
    let name = name.replace('/', "_");
    if is_folder(path) {
        let dir = path.components().as_path();
        let stem = dir
            .file_name()
            .map_or(fallback.into(), |s| s.to_string_lossy());
        let mut out = dir
            .with_file_name(format!("{stem}_{name}"))
            .into_os_string();
        out.push("/");
        return PathBuf::from(out);
    }
    let stem = path
        .file_stem()
        .map_or(fallback.into(), |s| s.to_string_lossy());
    path.with_file_name(format!("{stem}_{name}.mcap"))
}

/// The MCAP file of the bag `path` and, for a folder, the folder.
fn bag_layout(path: &Path) -> Result<(PathBuf, Option<PathBuf>)> {
    if !is_folder(path) {
        return Ok((path.to_path_buf(), None));
    }
    // `components` drops the trailing separator; a folder named `.` takes its real name.
    let dir = path.components().as_path().to_path_buf();
    let name = match dir.file_name() {
        Some(name) => name.to_os_string(),
        None => std::fs::canonicalize(&dir)
            .ok()
            .and_then(|d| d.file_name().map(std::ffi::OsStr::to_os_string))
            .with_context(|| format!("{}: the bag folder needs a name", path.display()))?,
    };
    let file = dir.join(format!("{}_0.mcap", name.to_string_lossy()));
    refuse_foreign_bag(&dir, &file)?;
    Ok((file, Some(dir)))
}

/// Refuses a bag folder that holds a bag sndt did not write, as rosbag2 refuses an existing
/// folder: a recording given as the output by mistake (`sndt map rec/ --mcap rec/`) would
/// otherwise be overwritten. sndt's own folder may be written again.
fn refuse_foreign_bag(dir: &Path, file: &Path) -> Result<()> {
    let name = file.file_name().map(|n| n.to_string_lossy().to_string());
    if dir.join(METADATA_FILE).exists() {
        let listed =
            MetadataFile::read(dir).map(|m| m.rosbag2_bagfile_information.relative_file_paths);
        if !matches!(&listed, Ok(files) if files.len() == 1 && Some(&files[0]) == name.as_ref()) {
            bail!(
                "{}: holds another bag ({METADATA_FILE} lists other files); sndt writes a bag \
                 folder only where none is or where it wrote one",
                dir.display()
            );
        }
    }
    if file.exists() && !written_by_sndt(file) {
        bail!(
            "{}: a bag that sndt did not write; give --mcap another folder",
            file.display()
        );
    }
    Ok(())
}

/// Whether the MCAP header of `file` names sndt as the writing library.
fn written_by_sndt(file: &Path) -> bool {
    use std::io::Read;
    let mut head = Vec::new();
    // The header is the first record: profile and library strings, well within 4 KiB.
    let read = File::open(file).and_then(|f| f.take(4096).read_to_end(&mut head));
    if read.is_err() {
        return false;
    }
    let first = mcap::read::LinearReader::new_with_options(
        &head,
        mcap::read::Options::IgnoreEndMagic.into(),
    )
    .ok()
    .and_then(|mut records| records.next());
    matches!(first, Some(Ok(mcap::records::Record::Header(h))) if h.library.starts_with("sndt "))
}

/// How a bag's chunks are compressed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum ChunkCompression {
    /// zstd (the default: small files; rosbag2 reads it).
    #[default]
    Zstd,
    /// lz4.
    Lz4,
    /// None, as `ros2 bag record` writes by default.
    None,
}

impl ChunkCompression {
    /// The mcap crate's setting.
    fn mcap(self) -> Option<mcap::Compression> {
        match self {
            ChunkCompression::Zstd => Some(mcap::Compression::Zstd),
            ChunkCompression::Lz4 => Some(mcap::Compression::Lz4),
            ChunkCompression::None => None,
        }
    }
}

impl BagWriter {
    /// Starts writing the bag `path` with zstd chunks: an `.mcap` file, or a bag folder
    /// when `path` ends in `/` or is an existing directory (see [`BagWriter`]).
    /// Directories are created.
    pub fn create(path: &Path) -> Result<BagWriter> {
        BagWriter::create_compressed(path, ChunkCompression::Zstd)
    }

    /// [`BagWriter::create`] with the chunks compressed as `compression` says.
    pub fn create_compressed(path: &Path, compression: ChunkCompression) -> Result<BagWriter> {
        let (file_path, folder) = bag_layout(path)?;
        let tmp = temporary(&file_path)?;
        let file = File::create(&tmp).with_context(|| format!("creating {}", path.display()))?;
        // As rosbag2's MCAP storage plugin: the `ros2` profile, which readers such as the
        // `rosbags` library require, and the distribution in a `rosbag2` metadata record.
        let library = format!(
            "sndt {} ({})",
            env!("CARGO_PKG_VERSION"),
            mcap::LIBRARY_IDENTIFIER
        );
        let mut writer = mcap::WriteOptions::new()
            .compression(compression.mcap())
            .profile("ros2")
            .library(library)
            .create(BufWriter::new(file))
            .with_context(|| format!("writing {}", path.display()))?;
        writer.write_metadata(&mcap::records::Metadata {
            name: "rosbag2".into(),
            metadata: BTreeMap::from([("ROS_DISTRO".into(), ROS_DISTRO.into())]),
        })?;
        Ok(BagWriter {
            writer,
            channels: HashMap::new(),
            topics: Vec::new(),
            span: None,
            sequence: 0,
            tmp,
            path: file_path,
            folder,
        })
    }

    /// Declares `topic` with the message type `(schema name, ros2msg definition)` and the
    /// QoS its publisher would offer ([`QosProfile::for_topic`]: `/tf_static` latched).
    pub fn add_topic(&mut self, topic: &str, kind: (&str, String)) -> Result<()> {
        self.add_topic_with_qos(topic, kind, QosProfile::for_topic(topic))
    }

    /// Declares `topic` with the message type `(schema name, ros2msg definition)`, recorded as
    /// offered with `qos` (the channel's `offered_qos_profiles`, which `ros2 bag play` offers
    /// again).
    pub fn add_topic_with_qos(
        &mut self,
        topic: &str,
        (name, definition): (&str, String),
        qos: QosProfile,
    ) -> Result<()> {
        if self.channels.contains_key(topic) {
            bail!("{topic}: topic declared twice");
        }
        let profiles = serialize_qos(&[qos])?;
        let schema = self
            .writer
            .add_schema(name, "ros2msg", definition.as_bytes())?;
        let metadata = BTreeMap::from([("offered_qos_profiles".to_string(), profiles.clone())]);
        let channel = self.writer.add_channel(schema, topic, "cdr", &metadata)?;
        self.channels
            .insert(topic.to_string(), (channel, self.topics.len()));
        self.topics.push(TopicWithMessageCount {
            topic_metadata: TopicMetadata {
                name: topic.into(),
                kind: name.into(),
                serialization_format: "cdr".into(),
                offered_qos_profiles: OfferedQos::Text(profiles),
                type_description_hash: None,
            },
            message_count: 0,
        });
        Ok(())
    }

    /// Writes `msg` (CDR, little-endian) on `topic` at `stamp` (log and publish time).
    pub fn write<T: Serialize>(&mut self, topic: &str, stamp: Time, msg: &T) -> Result<()> {
        let (channel_id, index) = *self
            .channels
            .get(topic)
            .ok_or_else(|| anyhow!("{topic}: topic not declared"))?;
        let data = msgs::to_cdr(msg).map_err(|e| anyhow!("{topic}: encoding CDR: {e}"))?;
        self.sequence += 1;
        let t = stamp.nanos();
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: self.sequence,
            log_time: t,
            publish_time: t,
        };
        self.writer.write_to_known_channel(&header, &data)?;
        self.topics[index].message_count += 1;
        self.span = Some(self.span.map_or((t, t), |(a, b)| (a.min(t), b.max(t))));
        Ok(())
    }

    /// Finishes the MCAP file (summary, footer) and puts it in place; for a bag folder, then
    /// writes its `metadata.yaml`.
    pub fn finish(mut self) -> Result<()> {
        let shown = self.path.display().to_string();
        self.writer
            .finish()
            .with_context(|| format!("writing {shown}"))?;
        self.writer
            .into_inner()
            .into_inner()
            .map_err(|e| anyhow!("writing {shown}: {}", e.error()))?;
        commit(&self.tmp, &self.path)?;
        let Some(dir) = &self.folder else {
            return Ok(());
        };
        let file = self.path.file_name().map(|n| n.to_string_lossy());
        let info = BagInfo::single_mcap(
            &file.unwrap_or_default(),
            self.topics,
            self.span.unwrap_or((0, 0)),
        );
        let yaml = MetadataFile {
            rosbag2_bagfile_information: info,
        }
        .to_yaml()?;
        write_bytes(&dir.join(METADATA_FILE), yaml)
    }
}

/// Topics and frames of the bags sndt writes.
pub mod names {
    /// Depth images (`16UC1`, millimetres).
    pub const DEPTH: &str = "/camera/depth/image_rect_raw";
    /// Labels (`mono8`, NYU40 class ids).
    pub const LABELS: &str = "/camera/semantic/labels";
    /// Camera info of the depth camera.
    pub const CAMERA_INFO: &str = "/camera/depth/camera_info";
    /// The world frame.
    pub const WORLD: &str = "world";
    /// The robot body, moved by `/tf`.
    pub const BASE: &str = "base_link";
    /// The depth camera's optical frame (x right, y down, z forward), fixed on the body.
    pub const CAMERA: &str = "camera_depth_optical_frame";
}

/// Time of frame `k` of a trajectory recorded at 10 Hz from t = 1 s.
pub fn frame_time(k: usize) -> Time {
    Time::from_nanos(1_000_000_000 + 100_000_000 * k as u64)
}

/// The camera info of a pinhole (ROS puts pixel centres at integer coordinates, sndt at
/// `col + 0.5`, hence the half pixel).
pub fn camera_info(header: Header, p: &sndt_core::Pinhole) -> CameraInfo {
    let (fx, fy) = (p.fx as f64, p.fy as f64);
    let (cx, cy) = (p.cx as f64 - 0.5, p.cy as f64 - 0.5);
    CameraInfo {
        header,
        height: p.height,
        width: p.width,
        distortion_model: "plumb_bob".into(),
        d: vec![0.0; 5],
        k: [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0],
        r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        p: [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0],
        ..CameraInfo::default()
    }
}

/// The camera pose as a ROS transform: the prepared layout's extrinsics record of the pose
/// (f64) turned to the optical frame by the exact component shuffle that
/// [`Extrinsics::to_pose`] applies, so a reader gets the prepared layout's pose.
pub fn camera_transform(pose: &sndt_core::Isometry3<f32>) -> Transform {
    let e = Extrinsics::from_pose(pose);
    // q_cv = q_gl * q_x(180°) = (w: -x, x: w, y: z, z: -y).
    Transform {
        translation: msgs::Vector3 {
            x: e.x,
            y: e.y,
            z: e.z,
        },
        rotation: msgs::Quaternion {
            x: e.quat_w,
            y: e.quat_z,
            z: -e.quat_y,
            w: -e.quat_x,
        },
    }
}

/// Writes one trajectory of frames as a ROS 2 bag: per frame a `16UC1` depth image (the
/// prepared layout's millimetres), `mono8` labels when the frame has them, the camera info,
/// and on `/tf` the body's pose in the world; `/tf_static` fixes the camera on the body
/// (identity, so the chain gives the frame's pose exactly).
pub fn write_trajectory(path: &Path, frames: impl Iterator<Item = Result<Frame>>) -> Result<usize> {
    write_trajectory_compressed(path, frames, ChunkCompression::Zstd)
}

/// [`write_trajectory`] with the chunks compressed as `compression` says.
pub fn write_trajectory_compressed(
    path: &Path,
    frames: impl Iterator<Item = Result<Frame>>,
    compression: ChunkCompression,
) -> Result<usize> {
    use names::*;
    let mut bag = BagWriter::create_compressed(path, compression)?;
    bag.add_topic(DEPTH, msgs::definitions::image())?;
    bag.add_topic(LABELS, msgs::definitions::image())?;
    bag.add_topic(CAMERA_INFO, msgs::definitions::camera_info())?;
    bag.add_topic("/tf", msgs::definitions::tf_message())?;
    bag.add_topic("/tf_static", msgs::definitions::tf_message())?;
    let fixed = TransformStamped {
        header: Header {
            stamp: frame_time(0),
            frame_id: BASE.into(),
        },
        child_frame_id: CAMERA.into(),
        transform: Transform::default(),
    };
    let tf_static = TfMessage {
        transforms: vec![fixed],
    };
    bag.write("/tf_static", frame_time(0), &tf_static)?;
    let mut n = 0;
    for (k, frame) in frames.enumerate() {
        let f = frame?;
        let Rays::Pinhole(cam) = *f.rays else {
            bail!("{}: only pinhole frames can be written as a bag", f.id);
        };
        let stamp = frame_time(k);
        let header = Header {
            stamp,
            frame_id: CAMERA.into(),
        };
        let body = TransformStamped {
            header: Header {
                stamp,
                frame_id: WORLD.into(),
            },
            child_frame_id: BASE.into(),
            transform: camera_transform(&f.pose),
        };
        bag.write(
            "/tf",
            stamp,
            &TfMessage {
                transforms: vec![body],
            },
        )?;
        bag.write(CAMERA_INFO, stamp, &camera_info(header.clone(), &cam))?;
        let mm: Vec<u8> = f
            .depth
            .iter()
            .flat_map(|&d| depth_to_mm(d).to_le_bytes())
            .collect();
        bag.write(DEPTH, stamp, &image(header.clone(), &cam, "16UC1", 2, mm))?;
        if let Some(labels) = &f.labels {
            bag.write(
                LABELS,
                stamp,
                &image(header, &cam, "mono8", 1, labels.clone()),
            )?;
        }
        n += 1;
    }
    bag.finish()?;
    Ok(n)
}

/// An image message of `cam`'s size with `bpp`-byte pixels, little-endian, unpadded rows.
pub fn image(
    header: Header,
    cam: &sndt_core::Pinhole,
    encoding: &str,
    bpp: u32,
    data: Vec<u8>,
) -> Image {
    Image {
        header,
        height: cam.height,
        width: cam.width,
        encoding: encoding.into(),
        is_bigendian: 0,
        step: cam.width * bpp,
        data,
    }
}
