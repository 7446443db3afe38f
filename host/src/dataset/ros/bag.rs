//! A ROS 2 recording (MCAP, CDR messages; one file or a rosbag2 folder) as a dataset:
//! depth images (`16UC1` millimetres or `32FC1` metres) paired with labels (`mono8` /
//! `8UC1`) and camera info by header stamp, posed by the transform chain from the camera's
//! frame to the world frame at the stamp. Topics are found by message type unless named.
//!
//! Opening a bag indexes it in one pass ([`BagIndex`]); a frame's images are read from the
//! file when the frame is loaded, so memory does not grow with the recording's length.

use super::index::{check_layout, decode, BagIndex, ImageRef, ODOMETRY, POSE_STAMPED};
pub use super::index::{TopicInfo, IMAGE};
use super::mcap_read::McapParts;
use super::msgs::{CameraInfo, Image, Transform, TransformStamped, Vector3};
use super::stamp_text;
use super::tf::{to_pose, TfBuffer};
use crate::dataset::frame::{Frame, FrameId, Rays};
pub use crate::dataset::source::BagOptions;
use crate::dataset::source::Dataset;
use anyhow::{anyhow, bail, Result};
use sndt_core::{validate_pose, DepthKind, Pinhole};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

/// A depth image and what was paired with it.
struct BagFrame {
    stamp: u64,
    depth: ImageRef,
    labels: Option<ImageRef>,
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
    label_map: Vec<(u8, u8)>,
    parts: McapParts,
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
            bail!("{what} topic {name} has no messages in the bag");
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
    /// Opens and indexes a bag: one `.mcap` file or a rosbag2 folder.
    pub fn open(path: &Path, o: &BagOptions) -> Result<Bag> {
        Bag::new(BagIndex::open(path)?, o)
    }

    /// [`Bag::open`] of a bag already in memory; `path` only names it (in errors, and its
    /// stem as the frames' scene).
    pub fn from_bytes(path: &Path, bytes: Vec<u8>, o: &BagOptions) -> Result<Bag> {
        Bag::new(BagIndex::scan(path, McapParts::from_bytes(path, bytes))?, o)
    }

    /// Chooses the topics and world frame of an indexed bag and pairs its depth images;
    /// an error says the first thing the bag lacks for mapping.
    pub fn new(mut index: BagIndex, o: &BagOptions) -> Result<Bag> {
        let topics = &index.topics;
        let depth_topic = pick(topics, &o.depth_topic, &["16UC1", "32FC1"], "depth")?
            .ok_or_else(|| anyhow!("{}: no depth images (16UC1 or 32FC1)", index.name))?;
        let labels_topic = pick(topics, &o.labels_topic, &["mono8", "8UC1"], "labels")?;
        if let Some(t) = &o.pose_topic {
            match topics.get(t).map(|i| i.schema.as_str()) {
                Some(POSE_STAMPED | ODOMETRY) => {}
                Some(other) => {
                    bail!("pose topic {t} has {other} messages, not {POSE_STAMPED} or {ODOMETRY}")
                }
                None => bail!("pose topic {t} has no messages in the bag"),
            }
        }
        let mut depths = index.images.remove(&depth_topic).unwrap_or_default();
        depths.sort_by_key(|d| d.stamp);
        let camera_frame = depths.first().map_or("", |d| d.frame_id.as_str());
        let tf = transforms(&index, o.pose_topic.as_deref(), camera_frame);
        let info_topic = camera_info_topic(&index, camera_frame, o)?;
        let infos = index.infos.remove(&info_topic).unwrap_or_default();
        let labels: BTreeMap<u64, ImageRef> = labels_topic
            .as_ref()
            .and_then(|t| index.images.remove(t))
            .unwrap_or_default()
            .into_iter()
            .map(|l| (l.stamp, l))
            .collect();
        let world = o.world_frame.clone().unwrap_or_else(|| "world".into());
        let mut bag = Bag {
            name: index.name,
            topics: index.topics,
            used: (depth_topic, labels_topic, info_topic, world),
            skipped: Vec::new(),
            ids: Vec::new(),
            frames: Vec::new(),
            label_map: o.label_map.clone(),
            parts: index.parts,
        };
        let paired = Paired {
            labels: &labels,
            infos: &infos,
            world_hint: world_hint(&tf, &bag.used.3),
            tf: &tf,
            tolerance: o.sync_tolerance_ns,
        };
        for depth in depths {
            let stamp = depth.stamp;
            match bag.pair(depth, &paired) {
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
    fn pair(&self, depth: ImageRef, p: &Paired) -> Result<BagFrame> {
        let (depth_topic, labels_topic, info_topic, world) = &self.used;
        let stamp = depth.stamp;
        let at = |topic: &str| format!("{topic} at {} s", stamp_text(stamp));
        check_image(&depth, &["16UC1", "32FC1"])
            .map_err(|e| anyhow!("{}: {e}", at(depth_topic)))?;
        let near = |t: u64| t.abs_diff(stamp) <= p.tolerance;
        let info = p
            .infos
            .iter()
            .min_by_key(|(t, _)| t.abs_diff(stamp))
            .filter(|(t, _)| near(*t))
            .ok_or_else(|| {
                anyhow!(
                    "{}: no camera info within the sync tolerance",
                    at(info_topic)
                )
            })?;
        let rectified = depth_topic.contains("rect");
        let camera = pinhole(&info.1, depth.size, rectified)
            .map_err(|e| anyhow!("{}: {e:#}", at(info_topic)))?;
        let labels = match labels_topic {
            None => None,
            Some(topic) => {
                let m = nearest(p.labels, stamp)
                    .filter(|(t, _)| near(*t))
                    .ok_or_else(|| anyhow!("{}: no labels within the sync tolerance", at(topic)))?
                    .1;
                check_image(m, &["mono8", "8UC1"]).map_err(|e| anyhow!("{}: {e}", at(topic)))?;
                if m.size != depth.size {
                    bail!(
                        "{}: labels are {}x{}, depth {}x{}",
                        at(topic),
                        m.size.0,
                        m.size.1,
                        depth.size.0,
                        depth.size.1
                    );
                }
                Some(m.clone())
            }
        };
        let pose =
            p.tf.lookup(world, &depth.frame_id, stamp)
                .map_err(|e| anyhow!("{}: {e:#}{}", at(depth_topic), p.world_hint))?;
        // The f32 pose the core gets: a transform chain can be finite in f64 and not in f32,
        // or far from a rotation; such a frame is skipped here, named, like other unusable
        // ones, not refused by the core while mapping.
        let pose = to_pose(&pose);
        if validate_pose(&pose).is_err() {
            bail!(
                "{}: the camera pose in {world} is not finite as f32 or its rotation is not unit",
                at(depth_topic)
            );
        }
        Ok(BagFrame {
            stamp,
            depth,
            labels,
            camera,
            pose,
        })
    }

    /// Stamps (ns) of the frames, in order.
    pub fn stamps(&self) -> Vec<u64> {
        self.frames.iter().map(|f| f.stamp).collect()
    }

    /// Reads an image message back from the recording, checked again (the file may have
    /// changed since it was indexed).
    fn image(&self, r: &ImageRef, topic: &str) -> Result<Image> {
        let data = self.parts.read(r.at)?;
        let m: Image = decode(topic, r.stamp, &data)?;
        if (m.width, m.height, &m.encoding) != (r.size.0, r.size.1, &r.encoding) {
            bail!(
                "{topic} at {} s: the image changed since the bag was opened",
                stamp_text(r.stamp)
            );
        }
        check_layout(&m).map_err(|e| anyhow!("{topic} at {} s: {e}", stamp_text(r.stamp)))?;
        Ok(m)
    }
}

/// What a depth image is paired with.
struct Paired<'a> {
    labels: &'a BTreeMap<u64, ImageRef>,
    infos: &'a [(u64, CameraInfo)],
    tf: &'a TfBuffer,
    tolerance: u64,
    /// Added to a failed lookup's reason: the roots to try when the world frame is not in
    /// the tree.
    world_hint: String,
}

/// When `world` is not a frame of the transform tree: a hint naming the tree's roots.
fn world_hint(tf: &TfBuffer, world: &str) -> String {
    if tf.frames().contains(world) {
        return String::new();
    }
    let roots = tf.roots();
    match roots.first() {
        None => format!(" (the bag has no transforms, so no frame reaches {world})"),
        Some(first) => format!(
            " (frame {world} is not in the transform tree, whose roots are {}: try --world-frame {first})",
            roots.join(", ")
        ),
    }
}

/// The transform buffer: poses from `pose_topic` become transforms (of the depth camera
/// for `PoseStamped`, of the odometry's child frame for `Odometry`) that replace the `/tf`
/// and `/tf_static` ones of that frame.
fn transforms(index: &BagIndex, pose_topic: Option<&str>, camera: &str) -> TfBuffer {
    let poses = pose_topic.and_then(|t| index.poses.get(t));
    let posed: Vec<TransformStamped> = poses
        .into_iter()
        .flatten()
        .map(|(child, header, pose)| TransformStamped {
            header: header.clone(),
            child_frame_id: child.clone().unwrap_or_else(|| camera.to_string()),
            transform: Transform {
                translation: Vector3 {
                    x: pose.position.x,
                    y: pose.position.y,
                    z: pose.position.z,
                },
                rotation: pose.orientation,
            },
        })
        .collect();
    let mut tf = TfBuffer::default();
    tf.add(&posed, false);
    let posed_frames: Vec<&String> = posed.iter().map(|t| &t.child_frame_id).collect();
    for (fixed, m) in &index.tfs {
        let keep: Vec<TransformStamped> = m
            .transforms
            .iter()
            .filter(|t| !posed_frames.contains(&&t.child_frame_id))
            .cloned()
            .collect();
        tf.add(&keep, *fixed);
    }
    tf.finish();
    tf
}

/// The camera-info topic: the one named, else the one in the depth images' frame, else
/// the only one.
fn camera_info_topic(index: &BagIndex, frame: &str, o: &BagOptions) -> Result<String> {
    if let Some(t) = &o.camera_info_topic {
        if !index.infos.contains_key(t) {
            bail!("camera-info topic {t} has no sensor_msgs/msg/CameraInfo messages in the bag");
        }
        return Ok(t.clone());
    }
    index
        .infos
        .iter()
        .find(|(_, v)| v.iter().any(|(_, m)| m.header.frame_id == frame))
        .or_else(|| index.infos.iter().next())
        .map(|(t, _)| t.clone())
        .ok_or_else(|| anyhow!("{}: no sensor_msgs/msg/CameraInfo topic", index.name))
}

/// Labels through a label map (`(id, class)`; unlisted ids become void); unchanged when
/// the map is empty.
fn map_labels(mut labels: Vec<u8>, map: &[(u8, u8)]) -> Vec<u8> {
    if !map.is_empty() {
        let mut table = [0u8; 256];
        for &(id, class) in map {
            table[id as usize] = class;
        }
        labels.iter_mut().for_each(|l| *l = table[*l as usize]);
    }
    labels
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

/// Checks a located image's encoding and that its data held its rows.
fn check_image(m: &ImageRef, encodings: &[&str]) -> Result<(), String> {
    if !encodings.contains(&m.encoding.as_str()) {
        return Err(format!(
            "encoding {:?}, expected one of {encodings:?}",
            m.encoding
        ));
    }
    m.layout_error.clone().map_or(Ok(()), Err)
}

/// The rows of an image without their padding, `bpp` bytes per pixel.
fn rows(m: &Image, bpp: usize) -> Vec<&[u8]> {
    let (w, step) = (m.width as usize * bpp, m.step as usize);
    (0..m.height as usize)
        .map(|r| &m.data[r * step..r * step + w])
        .collect()
}

/// The pinhole of a camera info for an image of that size: `K` for an image without
/// distortion, the projection `P` for a rectified one (whose `D` describes the raw image);
/// a raw image with distortion is refused. sndt's pixel centres are at `col + 0.5`, ROS's
/// at integers.
fn pinhole(info: &CameraInfo, (width, height): (u32, u32), rectified: bool) -> Result<Pinhole> {
    let distorted = info.d.iter().any(|&d| d != 0.0);
    if distorted && !rectified {
        bail!(
            "distortion model {:?} with non-zero coefficients on an unrectified image: give a rectified depth topic (image_rect...)",
            info.distortion_model
        );
    }
    if (info.width, info.height) != (width, height) {
        bail!(
            "camera info is {}x{}, the image {width}x{height}",
            info.width,
            info.height,
        );
    }
    let (k, p) = (info.k, info.p);
    let [fx, fy, cx, cy] = if rectified {
        [p[0], p[5], p[2], p[6]]
    } else {
        [k[0], k[4], k[2], k[5]]
    };
    let cam = Pinhole {
        fx: fx as f32,
        fy: fy as f32,
        cx: (cx + 0.5) as f32,
        cy: (cy + 0.5) as f32,
        width: info.width,
        height: info.height,
    };
    let ok = [cam.fx, cam.fy].iter().all(|f| f.is_finite() && *f > 0.0)
        && cam.cx.is_finite()
        && cam.cy.is_finite();
    if !ok {
        bail!("invalid intrinsics: K = {k:?}, P = {p:?}");
    }
    Ok(cam)
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
        let (depth_topic, labels_topic, ..) = &self.used;
        let depth = self.image(&f.depth, depth_topic)?;
        let labels = match (&f.labels, labels_topic) {
            (Some(r), Some(topic)) => {
                let m = self.image(r, topic)?;
                Some(map_labels(rows(&m, 1).concat(), &self.label_map))
            }
            _ => None,
        };
        Ok(Frame {
            id: id.clone(),
            pose: f.pose,
            rays: Arc::new(Rays::Pinhole(f.camera)),
            depth: depth_metres(&depth),
            depth_kind: DepthKind::Planar,
            labels,
            predictions: None,
        })
    }
}
