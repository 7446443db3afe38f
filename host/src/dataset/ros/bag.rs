//! A ROS 2 recording (MCAP, CDR messages) as a dataset: depth images (`16UC1` millimetres or
//! `32FC1` metres) paired with labels (`mono8` / `8UC1`) and camera info by header stamp,
//! posed by the transform chain from the camera's frame to the world frame at the stamp.
//! Topics are found by message type unless named.

use super::msgs::{
    CameraInfo, Image, Odometry, PoseStamped, TfMessage, Transform, TransformStamped, Vector3,
};
use super::tf::{to_pose, TfBuffer};
use crate::dataset::frame::{Frame, FrameId, Rays};
pub use crate::dataset::source::BagOptions;
use crate::dataset::source::Dataset;
use anyhow::{anyhow, bail, Context, Result};
use sndt_core::{validate_pose, DepthKind, Pinhole};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

/// Message type names.
const IMAGE: &str = "sensor_msgs/msg/Image";
const CAMERA_INFO: &str = "sensor_msgs/msg/CameraInfo";
const TF: &str = "tf2_msgs/msg/TFMessage";
const POSE_STAMPED: &str = "geometry_msgs/msg/PoseStamped";
const ODOMETRY: &str = "nav_msgs/msg/Odometry";

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

/// Longest record accepted, inside chunks too: 64 MiB, twenty 1024x768 float depth
/// images. Each record may be buffered at this size before its data turns out to be
/// missing, so the limit also bounds the memory a corrupt bag can take.
const MAX_RECORD_BYTES: usize = 1 << 26;

/// Reads every record once, chunks decompressed, refusing any longer than
/// [`MAX_RECORD_BYTES`]. The mcap crate's message stream trusts the lengths inside a chunk
/// and allocates whatever one claims, so a corrupt length would abort the process (or
/// take all memory) instead of failing.
fn check_record_lengths(bytes: &[u8]) -> Result<()> {
    use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
    let options = LinearReaderOptions::default().with_record_length_limit(MAX_RECORD_BYTES);
    let mut reader = LinearReader::new_with_options(options);
    let mut rest = bytes;
    while let Some(event) = reader.next_event() {
        let event = event.context("reading the MCAP file (truncated or corrupt?)")?;
        if let LinearReadEvent::ReadRequest(n) = event {
            let n = n.min(rest.len());
            reader.insert(n).copy_from_slice(&rest[..n]);
            reader.notify_read(n);
            rest = &rest[n..];
        }
    }
    Ok(())
}

/// Refuses an uncompressed chunk holding a record longer than what is left of the chunk.
/// The mcap crate (0.26) subtracts each such record's length from the chunk's remaining
/// bytes without checking, which underflows (a panic with overflow checks, as in debug
/// and fuzzing builds; garbage records without). Walks the top-level records as the
/// crate does; anything else malformed is left to the crate, which reports it.
fn check_uncompressed_chunks(bytes: &[u8]) -> Result<()> {
    const MAGIC_LEN: usize = 8;
    const CHUNK: u8 = 0x06;
    let mut at = MAGIC_LEN;
    while at < bytes.len() {
        let (Some(&opcode), Some(len)) = (bytes.get(at), le_u64(bytes, at + 1)) else {
            return Ok(());
        };
        let body = at + 9;
        if opcode == CHUNK {
            // Start and end times, uncompressed size and CRC, then the compression name
            // and the records' length.
            let Some(name_len) = le_bytes::<4>(bytes, body + 28).map(u32::from_le_bytes) else {
                return Ok(());
            };
            let name_end = body + 32 + name_len as usize;
            let (Some(name), Some(records_len)) =
                (bytes.get(body + 32..name_end), le_u64(bytes, name_end))
            else {
                return Ok(());
            };
            if name.is_empty() {
                check_chunk_records(bytes, name_end + 8, records_len)?;
            }
        }
        let Some(next) = usize::try_from(len).ok().and_then(|l| body.checked_add(l)) else {
            return Ok(());
        };
        at = next;
    }
    Ok(())
}

/// The records of an uncompressed chunk, `remaining` bytes from `at`: each must fit.
fn check_chunk_records(bytes: &[u8], mut at: usize, mut remaining: u64) -> Result<()> {
    while remaining > 0 {
        let Some(len) = at.checked_add(1).and_then(|l| le_u64(bytes, l)) else {
            return Ok(()); // truncated: the crate reports it
        };
        let record = len.saturating_add(9);
        if record > remaining {
            bail!("reading the MCAP file (truncated or corrupt?): a record of {record} bytes in a chunk with {remaining} bytes left");
        }
        remaining -= record;
        at = at.saturating_add(usize::try_from(record).unwrap_or(usize::MAX));
    }
    Ok(())
}

/// The `N` bytes at `at`, if the input has them.
fn le_bytes<const N: usize>(bytes: &[u8], at: usize) -> Option<[u8; N]> {
    bytes.get(at..at.checked_add(N)?)?.try_into().ok()
}

/// The little-endian `u64` at `at`, if the input has it.
fn le_u64(bytes: &[u8], at: usize) -> Option<u64> {
    le_bytes::<8>(bytes, at).map(u64::from_le_bytes)
}

/// Every CDR message of the bag.
fn messages(bytes: &[u8]) -> Result<Vec<RawMessage>> {
    check_uncompressed_chunks(bytes)?;
    check_record_lengths(bytes)?;
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
    /// Opens and indexes a bag.
    pub fn open(path: &Path, o: &BagOptions) -> Result<Bag> {
        let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
        Bag::from_bytes(path, bytes, o)
    }

    /// [`Bag::open`] of a bag already in memory; `path` only names it (in errors, and its
    /// stem as the frames' scene).
    pub fn from_bytes(path: &Path, bytes: Vec<u8>, o: &BagOptions) -> Result<Bag> {
        let msgs = messages(&bytes).with_context(|| format!("{}", path.display()))?;
        drop(bytes);
        let topics = topic_table(&msgs)?;
        let depth_topic = pick(&topics, &o.depth_topic, &["16UC1", "32FC1"], "depth")?
            .ok_or_else(|| anyhow!("{}: no depth images (16UC1 or 32FC1)", path.display()))?;
        let labels_topic = pick(&topics, &o.labels_topic, &["mono8", "8UC1"], "labels")?;
        if let Some(t) = &o.pose_topic {
            match topics.get(t).map(|i| i.schema.as_str()) {
                Some(POSE_STAMPED | ODOMETRY) => {}
                Some(other) => {
                    bail!("pose topic {t} has {other} messages, not {POSE_STAMPED} or {ODOMETRY}")
                }
                None => bail!("pose topic {t} has no messages in the bag"),
            }
        }
        let mut c = collect(
            &msgs,
            &depth_topic,
            labels_topic.as_deref(),
            o.pose_topic.as_deref(),
        )?;
        let info_topic = camera_info_topic(&c, o, path)?;
        let infos = c.infos.remove(&info_topic).unwrap_or_default();
        let world = o.world_frame.clone().unwrap_or_else(|| "world".into());
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
        let paired = Paired {
            labels: &c.labels,
            infos: &infos,
            tf: &c.tf,
            tolerance: o.sync_tolerance_ns,
            label_map: &o.label_map,
        };
        for depth in std::mem::take(&mut c.depths) {
            let stamp = depth.header.stamp.nanos();
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
    fn pair(&self, depth: Image, p: &Paired) -> Result<BagFrame> {
        let (depth_topic, labels_topic, info_topic, world) = &self.used;
        let stamp = depth.header.stamp.nanos();
        let at = |topic: &str| format!("{topic} at {:.9} s", stamp as f64 * 1e-9);
        check_image(&depth, &["16UC1", "32FC1"]).with_context(|| at(depth_topic))?;
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
        let camera = pinhole(&info.1, &depth, rectified).with_context(|| at(info_topic))?;
        let labels = match labels_topic {
            None => None,
            Some(topic) => {
                let m = nearest(p.labels, stamp)
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
                Some(map_labels(rows(m, 1).concat(), p.label_map))
            }
        };
        let pose =
            p.tf.lookup(world, &depth.header.frame_id, stamp)
                .with_context(|| at(depth_topic))?;
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
}

/// What a depth image is paired with.
struct Paired<'a> {
    labels: &'a BTreeMap<u64, Image>,
    infos: &'a [(u64, CameraInfo)],
    tf: &'a TfBuffer,
    tolerance: u64,
    label_map: &'a [(u8, u8)],
}

/// The messages sndt uses, decoded.
struct Collected {
    tf: TfBuffer,
    infos: BTreeMap<String, Vec<(u64, CameraInfo)>>,
    depths: Vec<Image>,
    labels: BTreeMap<u64, Image>,
}

/// Decodes the transforms, camera infos, depth and label images; poses from `pose_topic`
/// become transforms (of the depth camera for `PoseStamped`, of the odometry's child
/// frame for `Odometry`) that replace the `/tf` and `/tf_static` ones of that frame.
fn collect(
    msgs: &[RawMessage],
    depth_topic: &str,
    labels_topic: Option<&str>,
    pose_topic: Option<&str>,
) -> Result<Collected> {
    let mut c = Collected {
        tf: TfBuffer::default(),
        infos: BTreeMap::new(),
        depths: Vec::new(),
        labels: BTreeMap::new(),
    };
    let (mut tfs, mut poses) = (Vec::new(), Vec::new());
    for (topic, schema, t, data) in msgs {
        match schema.as_str() {
            TF => tfs.push((topic == "/tf_static", decode::<TfMessage>(topic, *t, data)?)),
            CAMERA_INFO => {
                let m: CameraInfo = decode(topic, *t, data)?;
                let entry = c.infos.entry(topic.clone()).or_default();
                entry.push((m.header.stamp.nanos(), m));
            }
            IMAGE if topic == depth_topic => c.depths.push(decode::<Image>(topic, *t, data)?),
            IMAGE if Some(topic.as_str()) == labels_topic => {
                let m: Image = decode(topic, *t, data)?;
                c.labels.insert(m.header.stamp.nanos(), m);
            }
            POSE_STAMPED if Some(topic.as_str()) == pose_topic => poses
                .push(decode::<PoseStamped>(topic, *t, data).map(|m| (None, m.header, m.pose))?),
            ODOMETRY if Some(topic.as_str()) == pose_topic => {
                let m: Odometry = decode(topic, *t, data)?;
                poses.push((Some(m.child_frame_id), m.header, m.pose.pose));
            }
            _ => {}
        }
    }
    c.depths.sort_by_key(|d| d.header.stamp.nanos());
    let camera = c
        .depths
        .first()
        .map_or(String::new(), |d| d.header.frame_id.clone());
    let posed: Vec<TransformStamped> = poses
        .into_iter()
        .map(|(child, header, pose)| TransformStamped {
            header,
            child_frame_id: child.unwrap_or_else(|| camera.clone()),
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
    c.tf.add(&posed, false);
    let posed_frames: Vec<&String> = posed.iter().map(|t| &t.child_frame_id).collect();
    for (fixed, m) in &tfs {
        let keep: Vec<TransformStamped> = m
            .transforms
            .iter()
            .filter(|t| !posed_frames.contains(&&t.child_frame_id))
            .cloned()
            .collect();
        c.tf.add(&keep, *fixed);
    }
    c.tf.finish();
    Ok(c)
}

/// The camera-info topic: the one named, else the one in the depth images' frame, else
/// the only one.
fn camera_info_topic(c: &Collected, o: &BagOptions, path: &Path) -> Result<String> {
    if let Some(t) = &o.camera_info_topic {
        if !c.infos.contains_key(t) {
            bail!("camera-info topic {t} has no sensor_msgs/msg/CameraInfo messages in the bag");
        }
        return Ok(t.clone());
    }
    let frame = c.depths.first().map_or("", |d| d.header.frame_id.as_str());
    c.infos
        .iter()
        .find(|(_, v)| v.iter().any(|(_, m)| m.header.frame_id == frame))
        .or_else(|| c.infos.iter().next())
        .map(|(t, _)| t.clone())
        .ok_or_else(|| anyhow!("{}: no sensor_msgs/msg/CameraInfo topic", path.display()))
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

/// The pinhole of a camera info for an image of that size: `K` for an image without
/// distortion, the projection `P` for a rectified one (whose `D` describes the raw image);
/// a raw image with distortion is refused. sndt's pixel centres are at `col + 0.5`, ROS's
/// at integers.
fn pinhole(info: &CameraInfo, image: &Image, rectified: bool) -> Result<Pinhole> {
    let distorted = info.d.iter().any(|&d| d != 0.0);
    if distorted && !rectified {
        bail!(
            "distortion model {:?} with non-zero coefficients on an unrectified image: give a rectified depth topic (image_rect...)",
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
