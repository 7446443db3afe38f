//! Writing ROS 2 recordings: an MCAP writer of CDR messages with `ros2msg` schemas (as
//! `ros2 bag record` writes them), and a synthetic trajectory as such a bag.

use crate::atomic::{commit, temporary};
use crate::dataset::frame::{Frame, Rays};
use crate::dataset::prepared::{depth_to_mm, Extrinsics};
use crate::dataset::ros::msgs::{
    self, CameraInfo, Header, Image, TfMessage, Time, Transform, TransformStamped,
};
use anyhow::{anyhow, bail, Context, Result};
use serde::Serialize;
use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// An MCAP file of ROS 2 messages, written into a temporary file that [`BagWriter::finish`]
/// syncs and renames over the target (a crash never leaves a truncated bag in its place).
pub struct BagWriter {
    writer: mcap::Writer<BufWriter<File>>,
    channels: HashMap<String, u16>,
    sequence: u32,
    tmp: PathBuf,
    path: PathBuf,
}

impl BagWriter {
    /// Starts writing `path` (its directory is created).
    pub fn create(path: &Path) -> Result<BagWriter> {
        let tmp = temporary(path)?;
        let file = File::create(&tmp).with_context(|| format!("creating {}", path.display()))?;
        let writer = mcap::Writer::new(BufWriter::new(file))
            .with_context(|| format!("writing {}", path.display()))?;
        Ok(BagWriter {
            writer,
            channels: HashMap::new(),
            sequence: 0,
            tmp,
            path: path.to_path_buf(),
        })
    }

    /// Declares `topic` with the message type `(schema name, ros2msg definition)`.
    pub fn add_topic(&mut self, topic: &str, (name, definition): (&str, String)) -> Result<()> {
        let schema = self
            .writer
            .add_schema(name, "ros2msg", definition.as_bytes())?;
        let channel = self
            .writer
            .add_channel(schema, topic, "cdr", &BTreeMap::new())?;
        self.channels.insert(topic.to_string(), channel);
        Ok(())
    }

    /// Writes `msg` (CDR, little-endian) on `topic` at `stamp` (log and publish time).
    pub fn write<T: Serialize>(&mut self, topic: &str, stamp: Time, msg: &T) -> Result<()> {
        let channel_id = *self
            .channels
            .get(topic)
            .ok_or_else(|| anyhow!("{topic}: topic not declared"))?;
        let data = cdr::serialize::<_, _, cdr::CdrLe>(msg, cdr::Infinite)
            .map_err(|e| anyhow!("{topic}: encoding CDR: {e}"))?;
        self.sequence += 1;
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: self.sequence,
            log_time: stamp.nanos(),
            publish_time: stamp.nanos(),
        };
        self.writer.write_to_known_channel(&header, &data)?;
        Ok(())
    }

    /// Finishes the file (summary, footer) and puts it in place.
    pub fn finish(mut self) -> Result<()> {
        let shown = self.path.display().to_string();
        self.writer
            .finish()
            .with_context(|| format!("writing {shown}"))?;
        self.writer
            .into_inner()
            .into_inner()
            .map_err(|e| anyhow!("writing {shown}: {}", e.error()))?;
        commit(&self.tmp, &self.path)
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
    use names::*;
    let mut bag = BagWriter::create(path)?;
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
