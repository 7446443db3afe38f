//! One pass over a recording ([`BagIndex::open`]): the topic table, every transform, camera
//! info and pose message decoded (they are small), and every image located but not kept
//! (its header and layout are), so the index stays small however long the recording is.
//! [`Bag`](super::bag::Bag) pairs the images into frames and reads them back one at a time.

use super::mcap_read::{Location, McapParts, ScannedMessage};
use super::msgs::{CameraInfo, Header, Image, Odometry, Pose, PoseStamped, TfMessage};
use super::stamp_text;
use super::tf::TfBuffer;
use anyhow::{anyhow, Context, Result};
use std::collections::BTreeMap;
use std::path::Path;

/// Message type names.
pub const IMAGE: &str = "sensor_msgs/msg/Image";
/// Camera info.
pub const CAMERA_INFO: &str = "sensor_msgs/msg/CameraInfo";
/// Transforms (`/tf`, `/tf_static`).
pub const TF: &str = "tf2_msgs/msg/TFMessage";
/// A pose of the depth camera.
pub const POSE_STAMPED: &str = "geometry_msgs/msg/PoseStamped";
/// A pose of a body.
pub const ODOMETRY: &str = "nav_msgs/msg/Odometry";

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

impl TopicInfo {
    /// Messages per second over the topic's log times (`None` for fewer than two messages
    /// or no time between them).
    ///
    /// ```
    /// use sndt_host::dataset::ros::index::TopicInfo;
    /// let t = TopicInfo { count: 11, time_range: (1_000_000_000, 2_000_000_000), ..Default::default() };
    /// assert_eq!(t.rate_hz(), Some(10.0));
    /// ```
    pub fn rate_hz(&self) -> Option<f64> {
        let span = self.time_range.1.saturating_sub(self.time_range.0);
        (self.count > 1 && span > 0).then(|| (self.count - 1) as f64 / (span as f64 * 1e-9))
    }
}

/// An image message located in the recording: its header, layout and whether its data
/// fits the layout (checked when it was scanned).
#[derive(Clone, Debug)]
pub struct ImageRef {
    /// Header stamp, ns.
    pub stamp: u64,
    /// Camera frame.
    pub frame_id: String,
    /// Pixel encoding.
    pub encoding: String,
    /// Columns and rows.
    pub size: (u32, u32),
    /// Why the data does not fit the layout, if it does not.
    pub layout_error: Option<String>,
    /// Where the message is.
    pub at: Location,
}

/// A pose message: the child frame (odometry) or `None` (the depth camera), header, pose.
pub type PoseMessage = (Option<String>, Header, Pose);

/// What one pass over a recording found.
pub struct BagIndex {
    /// Name of the recording (file stem, or the folder's name).
    pub name: String,
    /// Topic name -> info.
    pub topics: BTreeMap<String, TopicInfo>,
    /// `/tf` and `/tf_static` messages (`true` for static), in file order.
    pub tfs: Vec<(bool, TfMessage)>,
    /// Camera infos by topic: (header stamp ns, message).
    pub infos: BTreeMap<String, Vec<(u64, CameraInfo)>>,
    /// Images by topic, in file order.
    pub images: BTreeMap<String, Vec<ImageRef>>,
    /// Pose and odometry messages by topic.
    pub poses: BTreeMap<String, Vec<PoseMessage>>,
    /// The files, to read the images from.
    pub parts: McapParts,
}

/// Decodes a CDR message.
pub fn decode<T: serde::de::DeserializeOwned>(topic: &str, stamp: u64, data: &[u8]) -> Result<T> {
    crate::dataset::ros::msgs::from_cdr(data).map_err(|e| {
        anyhow!(
            "{topic} at {} s: not a valid CDR message: {e}",
            stamp_text(stamp)
        )
    })
}

impl BagIndex {
    /// Indexes the recording at `path`: one `.mcap` file, or a rosbag2 folder
    /// (`metadata.yaml` and its split `.mcap` files, read in order).
    pub fn open(path: &Path) -> Result<BagIndex> {
        let files = if path.is_dir() {
            super::metadata::bag_files(path)?
        } else {
            vec![path.to_path_buf()]
        };
        let parts = McapParts::open(&files)?;
        BagIndex::scan(path, parts)
    }

    /// Indexes the files of `parts`; `path` names the recording.
    pub fn scan(path: &Path, parts: McapParts) -> Result<BagIndex> {
        let name = path
            .file_stem()
            .map_or("bag".into(), |s| s.to_string_lossy().into_owned());
        let mut index = BagIndex {
            name,
            topics: BTreeMap::new(),
            tfs: Vec::new(),
            infos: BTreeMap::new(),
            images: BTreeMap::new(),
            poses: BTreeMap::new(),
            parts: McapParts::empty(),
        };
        parts
            .scan(|m| index.add(&m))
            .with_context(|| path.display().to_string())?;
        index.parts = parts;
        Ok(index)
    }

    /// Counts a message in the topic table and keeps what sndt uses of it.
    fn add(&mut self, m: &ScannedMessage) -> Result<()> {
        if m.encoding != "cdr" {
            return Ok(());
        }
        let (topic, t) = (m.topic, m.log_time);
        let info = self
            .topics
            .entry(topic.to_string())
            .or_insert_with(|| TopicInfo {
                schema: m.schema.to_string(),
                time_range: (t, t),
                ..TopicInfo::default()
            });
        info.count += 1;
        info.time_range = (info.time_range.0.min(t), info.time_range.1.max(t));
        match m.schema {
            TF => self
                .tfs
                .push((topic == "/tf_static", decode(topic, t, m.data)?)),
            CAMERA_INFO => {
                let c: CameraInfo = decode(topic, t, m.data)?;
                let list = self.infos.entry(topic.to_string()).or_default();
                list.push((c.header.stamp.nanos(), c));
            }
            IMAGE => {
                let image: Image = decode(topic, t, m.data)?;
                info.encoding.get_or_insert_with(|| image.encoding.clone());
                let list = self.images.entry(topic.to_string()).or_default();
                list.push(ImageRef {
                    stamp: image.header.stamp.nanos(),
                    layout_error: check_layout(&image).err(),
                    frame_id: image.header.frame_id,
                    encoding: image.encoding,
                    size: (image.width, image.height),
                    at: m.at,
                });
            }
            POSE_STAMPED => {
                let p: PoseStamped = decode(topic, t, m.data)?;
                let list = self.poses.entry(topic.to_string()).or_default();
                list.push((None, p.header, p.pose));
            }
            ODOMETRY => {
                let o: Odometry = decode(topic, t, m.data)?;
                let list = self.poses.entry(topic.to_string()).or_default();
                list.push((Some(o.child_frame_id), o.header, o.pose.pose));
            }
            _ => {}
        }
        Ok(())
    }

    /// The transforms of `/tf` and `/tf_static` alone (no pose topic), for a look at the
    /// tree.
    pub fn tf_tree(&self) -> TfBuffer {
        let mut tf = TfBuffer::default();
        for (fixed, m) in &self.tfs {
            tf.add(&m.transforms, *fixed);
        }
        tf.finish();
        tf
    }
}

/// Bytes per pixel of an encoding as the reader treats it (1 but for 16- and 32-bit ones).
pub fn bytes_per_pixel(encoding: &str) -> usize {
    if encoding.starts_with("32") {
        4
    } else if encoding.starts_with("16") {
        2
    } else {
        1
    }
}

/// Checks that an image's data holds its rows.
pub fn check_layout(m: &Image) -> Result<(), String> {
    let bpp = bytes_per_pixel(&m.encoding);
    let (w, h, step) = (m.width as usize, m.height as usize, m.step as usize);
    let fits = w > 0 && h > 0 && step >= w * bpp && m.data.len() >= step * h;
    if !fits {
        return Err(format!(
            "{w}x{h} image with step {step} and {} bytes of data",
            m.data.len()
        ));
    }
    Ok(())
}
