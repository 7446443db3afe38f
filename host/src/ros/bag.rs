//! A ROS 2 recording (MCAP, CDR messages) as a dataset: depth images (`16UC1` millimetres or
//! `32FC1` metres) paired with labels (`mono8` / `8UC1`) and camera info by header stamp,
//! posed by the transform chain from the camera's frame to the world frame at the stamp.
//! Topics are found by message type unless named.

use super::msgs::{CameraInfo, Image, TfMessage};
use super::tf::{to_pose, TfBuffer};
use crate::dataset::frame::{Frame, FrameId, Rays};
pub use crate::dataset::source::BagOptions;
use crate::dataset::source::Dataset;
use anyhow::{anyhow, bail, Context, Result};
use sndt_core::{DepthKind, Pinhole};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

/// Message type names.
const IMAGE: &str = "sensor_msgs/msg/Image";
const CAMERA_INFO: &str = "sensor_msgs/msg/CameraInfo";
const TF: &str = "tf2_msgs/msg/TFMessage";

/// One topic of a bag.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TopicInfo {
    /// Message type (schema name).
    pub schema: String,
    /// Messages.
    pub count: usize,
    /// First and last log time, ns.
    pub time_range: (u64, u64),
    /// Encoding of the first image (image topics).
    pub encoding: Option<String>,
}

/// A depth image and what was paired with it.
struct BagFrame {
    stamp: u64,
    depth: Image,
    labels: Option<Vec<u8>>,
    camera: Pinhole,
    pose: sndt_core::Isometry3<f32>,
}

/// An opened bag.
pub struct Bag {
    name: String,
    /// Topic name -> info.
    pub topics: BTreeMap<String, TopicInfo>,
    /// The topics used: depth, labels, camera info; and the world frame.
    pub used: (String, Option<String>, String, String),
    /// Depth images that could not be used, with the reason.
    pub skipped: Vec<(u64, String)>,
    ids: Vec<FrameId>,
    frames: Vec<BagFrame>,
}

/// Decodes a CDR message.
fn decode<T: serde::de::DeserializeOwned>(topic: &str, log_time: u64, data: &[u8]) -> Result<T> {
    cdr::deserialize::<T>(data).map_err(|e| {
        anyhow!(
            "{topic} at {:.9} s: not a valid CDR message: {e}",
            log_time as f64 * 1e-9
        )
    })
}

/// A CDR message of the bag: topic, schema name, log time, bytes.
type RawMessage = (String, String, u64, Vec<u8>);

/// Every CDR message of the bag.
fn messages(bytes: &[u8]) -> Result<Vec<RawMessage>> {
    let mut out = Vec::new();
    for m in mcap::MessageStream::new(bytes).context("not an MCAP file")? {
        let m = m.context("reading the MCAP file (truncated or corrupt?)")?;
        let schema = m
            .channel
            .schema
            .as_ref()
            .map_or(String::new(), |s| s.name.clone());
        if m.channel.message_encoding != "cdr" {
            continue;
        }
        out.push((
            m.channel.topic.clone(),
            schema,
            m.log_time,
            m.data.into_owned(),
        ));
    }
    Ok(out)
}

/// Topic table of a bag's messages (the first image of each image topic decoded for its
/// encoding).
fn topic_table(msgs: &[RawMessage]) -> Result<BTreeMap<String, TopicInfo>> {
    let mut topics: BTreeMap<String, TopicInfo> = BTreeMap::new();
    for (topic, schema, t, data) in msgs {
        let info = topics.entry(topic.clone()).or_insert_with(|| TopicInfo {
            schema: schema.clone(),
            time_range: (*t, *t),
            ..TopicInfo::default()
        });
        info.count += 1;
        info.time_range = (info.time_range.0.min(*t), info.time_range.1.max(*t));
        if schema == IMAGE && info.encoding.is_none() {
            info.encoding = Some(decode::<Image>(topic, *t, data)?.encoding);
        }
    }
    Ok(topics)
}

/// The image topic whose encoding is one of `encodings`, or the one named.
fn pick(
    topics: &BTreeMap<String, TopicInfo>,
    named: &Option<String>,
    encodings: &[&str],
    what: &str,
) -> Result<Option<String>> {
    if let Some(name) = named {
        let Some(info) = topics.get(name) else {
            bail!("{what} topic {name} is not in the bag");
        };
        if info.schema != IMAGE {
            bail!(
                "{what} topic {name} has {} messages, not {IMAGE}",
                info.schema
            );
        }
        return Ok(Some(name.clone()));
    }
    let found: Vec<&String> = topics
        .iter()
        .filter(|(_, i)| {
            i.encoding
                .as_deref()
                .is_some_and(|e| encodings.contains(&e))
        })
        .map(|(t, _)| t)
        .collect();
    match found.as_slice() {
        [] => Ok(None),
        [one] => Ok(Some((*one).clone())),
        many => bail!("several {what} topics ({many:?}): choose one with --{what}-topic"),
    }
}

impl Bag {
    /// Opens and indexes a bag.
    pub fn open(path: &Path, o: &BagOptions) -> Result<Bag> {
        let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
        let msgs = messages(&bytes).with_context(|| format!("{}", path.display()))?;
        drop(bytes);
        let topics = topic_table(&msgs)?;
        let depth_topic = pick(&topics, &o.depth_topic, &["16UC1", "32FC1"], "depth")?
            .ok_or_else(|| anyhow!("{}: no depth images (16UC1 or 32FC1)", path.display()))?;
        let labels_topic = pick(&topics, &o.labels_topic, &["mono8", "8UC1"], "labels")?;
        let mut tf = TfBuffer::default();
        let mut infos: BTreeMap<String, Vec<(u64, CameraInfo)>> = BTreeMap::new();
        let (mut depths, mut labels) = (Vec::new(), BTreeMap::new());
        for (topic, schema, t, data) in &msgs {
            match schema.as_str() {
                TF => {
                    let m: TfMessage = decode(topic, *t, data)?;
                    tf.add(&m.transforms, topic == "/tf_static");
                }
                CAMERA_INFO => {
                    let m: CameraInfo = decode(topic, *t, data)?;
                    infos
                        .entry(topic.clone())
                        .or_default()
                        .push((m.header.stamp.nanos(), m));
                }
                IMAGE if *topic == depth_topic => depths.push(decode::<Image>(topic, *t, data)?),
                IMAGE if Some(topic) == labels_topic.as_ref() => {
                    let m: Image = decode(topic, *t, data)?;
                    labels.insert(m.header.stamp.nanos(), m);
                }
                _ => {}
            }
        }
        tf.finish();
        let frame_id = depths
            .first()
            .map_or(String::new(), |d| d.header.frame_id.clone());
        let info_topic = match &o.camera_info_topic {
            Some(t) => t.clone(),
            None => infos
                .iter()
                .find(|(_, v)| v.iter().any(|(_, m)| m.header.frame_id == frame_id))
                .or_else(|| infos.iter().next())
                .map(|(t, _)| t.clone())
                .ok_or_else(|| {
                    anyhow!("{}: no sensor_msgs/msg/CameraInfo topic", path.display())
                })?,
        };
        let infos = infos
            .remove(&info_topic)
            .ok_or_else(|| anyhow!("camera-info topic {info_topic} is not in the bag"))?;
        let world = o.world_frame.clone().unwrap_or_else(|| "world".into());
        depths.sort_by_key(|d| d.header.stamp.nanos());
        let mut bag = Bag {
            name: path
                .file_stem()
                .map_or("bag".into(), |s| s.to_string_lossy().into_owned()),
            topics,
            used: (depth_topic, labels_topic, info_topic, world),
            skipped: Vec::new(),
            ids: Vec::new(),
            frames: Vec::new(),
        };
        for depth in depths {
            let stamp = depth.header.stamp.nanos();
            match bag.pair(depth, &labels, &infos, &tf, o.sync_tolerance_ns) {
                Ok(f) => bag.frames.push(f),
                Err(e) => bag.skipped.push((stamp, format!("{e:#}"))),
            }
        }
        bag.ids = (0..bag.frames.len())
            .map(|k| FrameId {
                scene: bag.name.clone(),
                cam: "cam_00".into(),
                index: k as u32,
            })
            .collect();
        Ok(bag)
    }

    /// Pairs a depth image with its labels, camera and pose.
    fn pair(
        &self,
        depth: Image,
        labels: &BTreeMap<u64, Image>,
        infos: &[(u64, CameraInfo)],
        tf: &TfBuffer,
        tolerance: u64,
    ) -> Result<BagFrame> {
        let (depth_topic, labels_topic, info_topic, world) = &self.used;
        let stamp = depth.header.stamp.nanos();
        let at = |topic: &str| format!("{topic} at {:.9} s", stamp as f64 * 1e-9);
        check_image(&depth, &["16UC1", "32FC1"]).with_context(|| at(depth_topic))?;
        let near = |t: u64| t.abs_diff(stamp) <= tolerance;
        let info = infos
            .iter()
            .min_by_key(|(t, _)| t.abs_diff(stamp))
            .filter(|(t, _)| near(*t))
            .ok_or_else(|| {
                anyhow!(
                    "{}: no camera info within the sync tolerance",
                    at(info_topic)
                )
            })?;
        let camera = pinhole(&info.1, &depth).with_context(|| at(info_topic))?;
        let labels = match labels_topic {
            None => None,
            Some(topic) => {
                let m = nearest(labels, stamp)
                    .filter(|(t, _)| near(*t))
                    .ok_or_else(|| anyhow!("{}: no labels within the sync tolerance", at(topic)))?
                    .1;
                check_image(m, &["mono8", "8UC1"]).with_context(|| at(topic))?;
                if (m.width, m.height) != (depth.width, depth.height) {
                    bail!(
                        "{}: labels are {}x{}, depth {}x{}",
                        at(topic),
                        m.width,
                        m.height,
                        depth.width,
                        depth.height
                    );
                }
                Some(rows(m, 1).concat())
            }
        };
        let pose = tf
            .lookup(world, &depth.header.frame_id, stamp)
            .with_context(|| at(depth_topic))?;
        Ok(BagFrame {
            stamp,
            depth,
            labels,
            camera,
            pose: to_pose(&pose),
        })
    }

    /// Stamps (ns) of the frames, in order.
    pub fn stamps(&self) -> Vec<u64> {
        self.frames.iter().map(|f| f.stamp).collect()
    }
}

/// The entry of `map` nearest to `stamp`.
fn nearest<T>(map: &BTreeMap<u64, T>, stamp: u64) -> Option<(u64, &T)> {
    let after = map.range(stamp..).next();
    let before = map.range(..stamp).next_back();
    [before, after]
        .into_iter()
        .flatten()
        .min_by_key(|(t, _)| t.abs_diff(stamp))
        .map(|(t, v)| (*t, v))
}

/// Checks an image's encoding and size.
fn check_image(m: &Image, encodings: &[&str]) -> Result<()> {
    if !encodings.contains(&m.encoding.as_str()) {
        bail!("encoding {:?}, expected one of {encodings:?}", m.encoding);
    }
    let bpp = if m.encoding.starts_with("32") {
        4
    } else if m.encoding.starts_with("16") {
        2
    } else {
        1
    };
    let (w, h, step) = (m.width as usize, m.height as usize, m.step as usize);
    if w == 0 || h == 0 || step < w * bpp || m.data.len() < step * h {
        bail!(
            "{}x{} image with step {} and {} bytes of data",
            w,
            h,
            step,
            m.data.len()
        );
    }
    Ok(())
}

/// The rows of an image without their padding, `bpp` bytes per pixel.
fn rows(m: &Image, bpp: usize) -> Vec<&[u8]> {
    let (w, step) = (m.width as usize * bpp, m.step as usize);
    (0..m.height as usize)
        .map(|r| &m.data[r * step..r * step + w])
        .collect()
}

/// The pinhole of a camera info for an image of that size (sndt's pixel centres are at
/// `col + 0.5`, ROS's at integers).
fn pinhole(info: &CameraInfo, image: &Image) -> Result<Pinhole> {
    if info.d.iter().any(|&d| d != 0.0) {
        bail!(
            "distortion model {:?} with non-zero coefficients: sndt needs rectified depth (a rect topic with zero distortion)",
            info.distortion_model
        );
    }
    if (info.width, info.height) != (image.width, image.height) {
        bail!(
            "camera info is {}x{}, the image {}x{}",
            info.width,
            info.height,
            image.width,
            image.height
        );
    }
    let k = info.k;
    let p = Pinhole {
        fx: k[0] as f32,
        fy: k[4] as f32,
        cx: (k[2] + 0.5) as f32,
        cy: (k[5] + 0.5) as f32,
        width: info.width,
        height: info.height,
    };
    let ok = [p.fx, p.fy].iter().all(|f| f.is_finite() && *f > 0.0)
        && p.cx.is_finite()
        && p.cy.is_finite();
    if !ok {
        bail!("invalid intrinsics K = {k:?}");
    }
    Ok(p)
}

/// Depth in metres of a checked depth image: `16UC1` millimetres as the prepared layout
/// converts them, `32FC1` as is (0, NaN and inf stay: the core treats them as no return).
fn depth_metres(m: &Image) -> Vec<f32> {
    let big = m.is_bigendian != 0;
    if m.encoding == "16UC1" {
        rows(m, 2)
            .iter()
            .flat_map(|r| r.chunks_exact(2))
            .map(|b| {
                let v = if big {
                    u16::from_be_bytes([b[0], b[1]])
                } else {
                    u16::from_le_bytes([b[0], b[1]])
                };
                v as f32 / 1000.0
            })
            .collect()
    } else {
        rows(m, 4)
            .iter()
            .flat_map(|r| r.chunks_exact(4))
            .map(|b| {
                let b = [b[0], b[1], b[2], b[3]];
                if big {
                    f32::from_be_bytes(b)
                } else {
                    f32::from_le_bytes(b)
                }
            })
            .collect()
    }
}

impl Dataset for Bag {
    fn describe(&self) -> String {
        let (d, l, c, w) = &self.used;
        format!(
            "ROS 2 bag {}: {} frames from {d} (labels {}, camera info {c}, poses in {w}), {} skipped",
            self.name,
            self.frames.len(),
            l.as_deref().unwrap_or("none"),
            self.skipped.len()
        )
    }

    fn frames(&self) -> &[FrameId] {
        &self.ids
    }

    fn stamp(&self, id: &FrameId) -> Option<u64> {
        self.frames.get(id.index as usize).map(|f| f.stamp)
    }

    fn load(&self, id: &FrameId) -> Result<Frame> {
        let f = self
            .frames
            .get(id.index as usize)
            .filter(|_| id.scene == self.name)
            .ok_or_else(|| anyhow!("{id}: not a frame of bag {}", self.name))?;
        Ok(Frame {
            id: id.clone(),
            pose: f.pose,
            rays: Arc::new(Rays::Pinhole(f.camera)),
            depth: depth_metres(&f.depth),
            depth_kind: DepthKind::Planar,
            labels: f.labels.clone(),
            predictions: None,
        })
    }
}
