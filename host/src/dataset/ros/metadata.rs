//! rosbag2's bag folder: `metadata.yaml` (`rosbag2_bagfile_information`) beside the storage
//! files it lists, as `ros2 bag record` leaves it; and the QoS profiles that rosbag2 records
//! per topic (`offered_qos_profiles`), which `ros2 bag play` offers again on playback.
//!
//! The structs read what the rosbag2 releases write (version 4 to 9: later fields are
//! optional, and `offered_qos_profiles` is a YAML string up to version 8, a list from 9 on)
//! and write what Humble writes (version 5). [`bag_files`] lists a folder's MCAP files in
//! the order of its `metadata.yaml`.

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The ROS 2 distribution whose bag format sndt writes.
pub const ROS_DISTRO: &str = "humble";

/// The `metadata.yaml` version that rosbag2 on Humble writes.
pub const HUMBLE_VERSION: u32 = 5;

/// The file of a bag folder that describes it.
pub const METADATA_FILE: &str = "metadata.yaml";

/// The whole `metadata.yaml`: one top-level key.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MetadataFile {
    /// The bag's description.
    pub rosbag2_bagfile_information: BagInfo,
}

/// A bag as `metadata.yaml` describes it. The field order is the order rosbag2 writes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BagInfo {
    /// Format version (Humble: 5).
    pub version: u32,
    /// Storage plugin: `mcap` or `sqlite3`.
    pub storage_identifier: String,
    /// Last message time minus the first.
    pub duration: Duration,
    /// Time of the first message.
    pub starting_time: StartingTime,
    /// Messages in all files.
    pub message_count: u64,
    /// Every topic with its message count.
    pub topics_with_message_count: Vec<TopicWithMessageCount>,
    /// rosbag2's own compression of files or messages (`zstd`), empty for none; MCAP's chunk
    /// compression is inside the files and not stated here.
    #[serde(default)]
    pub compression_format: String,
    /// `file`, `message`, or empty for none.
    #[serde(default)]
    pub compression_mode: String,
    /// The storage files, relative to the folder, in recording order.
    pub relative_file_paths: Vec<String>,
    /// Per file: time span and message count (version 5 on).
    #[serde(default)]
    pub files: Vec<FileInfo>,
    /// Free key-value pairs (version 6 on).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub custom_data: Option<BTreeMap<String, String>>,
    /// The distribution that recorded the bag (version 8 on).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ros_distro: Option<String>,
}

/// A duration in nanoseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Duration {
    /// Nanoseconds.
    pub nanoseconds: u64,
}

/// A time in nanoseconds since the epoch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct StartingTime {
    /// Nanoseconds since the epoch.
    pub nanoseconds_since_epoch: u64,
}

/// A topic and how many messages it has.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TopicWithMessageCount {
    /// Name, type, encoding and QoS.
    pub topic_metadata: TopicMetadata,
    /// Messages on the topic.
    pub message_count: u64,
}

/// What rosbag2 records about a topic.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TopicMetadata {
    /// Topic name.
    pub name: String,
    /// Message type, e.g. `sensor_msgs/msg/Image`.
    #[serde(rename = "type")]
    pub kind: String,
    /// Message encoding: `cdr`.
    pub serialization_format: String,
    /// The publishers' QoS profiles.
    #[serde(default)]
    pub offered_qos_profiles: OfferedQos,
    /// RIHS01 hash of the type (version 7 on).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub type_description_hash: Option<String>,
}

/// `offered_qos_profiles` as the versions write it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum OfferedQos {
    /// Up to version 8 (Humble): a YAML document in a string, enums as integers.
    Text(String),
    /// Version 9 on: a list of profiles, enums as names. Kept as read.
    List(Vec<yaml_serde::Value>),
}

impl Default for OfferedQos {
    fn default() -> OfferedQos {
        OfferedQos::Text(String::new())
    }
}

/// A time span of a QoS policy.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct QosTime {
    /// Seconds.
    pub sec: u64,
    /// Nanoseconds.
    pub nsec: u64,
}

impl QosTime {
    /// `RMW_DURATION_INFINITE` (i64::MAX ns) as a Humble recording states deadlines, lifespans
    /// and lease durations that a publisher left at their defaults.
    pub const INFINITE: QosTime = QosTime {
        sec: 9_223_372_036,
        nsec: 854_775_807,
    };
}

/// A QoS profile with rmw's enum values, in rosbag2's field order (Humble's
/// `rosbag2_transport` writes these integers).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct QosProfile {
    /// 1 keep last, 2 keep all, 3 unknown.
    pub history: u8,
    /// Queue depth with keep last.
    pub depth: u32,
    /// 1 reliable, 2 best effort.
    pub reliability: u8,
    /// 1 transient local (late subscribers get the last messages), 2 volatile.
    pub durability: u8,
    /// Deadline.
    pub deadline: QosTime,
    /// Lifespan.
    pub lifespan: QosTime,
    /// 1 automatic.
    pub liveliness: u8,
    /// Liveliness lease duration.
    pub liveliness_lease_duration: QosTime,
    /// Whether the topic name skips ROS naming conventions.
    pub avoid_ros_namespace_conventions: bool,
}

impl QosProfile {
    /// `RMW_QOS_POLICY_HISTORY_KEEP_LAST`.
    pub const KEEP_LAST: u8 = 1;
    /// `RMW_QOS_POLICY_RELIABILITY_RELIABLE`.
    pub const RELIABLE: u8 = 1;
    /// `RMW_QOS_POLICY_DURABILITY_TRANSIENT_LOCAL`.
    pub const TRANSIENT_LOCAL: u8 = 1;
    /// `RMW_QOS_POLICY_DURABILITY_VOLATILE`.
    pub const VOLATILE: u8 = 2;
    /// `RMW_QOS_POLICY_LIVELINESS_AUTOMATIC`.
    pub const AUTOMATIC: u8 = 1;

    /// A reliable, keep-last publisher of `durability` with the rest at rmw's defaults.
    fn reliable(depth: u32, durability: u8) -> QosProfile {
        QosProfile {
            history: Self::KEEP_LAST,
            depth,
            reliability: Self::RELIABLE,
            durability,
            deadline: QosTime::INFINITE,
            lifespan: QosTime::INFINITE,
            liveliness: Self::AUTOMATIC,
            liveliness_lease_duration: QosTime::INFINITE,
            avoid_ros_namespace_conventions: false,
        }
    }

    /// rclcpp's default publisher: reliable, volatile, keep last 10.
    pub fn volatile() -> QosProfile {
        QosProfile::reliable(10, Self::VOLATILE)
    }

    /// A latched publisher as tf2's static broadcaster offers it: reliable, transient local,
    /// keep last 1, so a subscriber that comes later still gets the last message.
    pub fn latched() -> QosProfile {
        QosProfile::reliable(1, Self::TRANSIENT_LOCAL)
    }

    /// The profile a topic's publisher offers in ROS 2: latched for `/tf_static` (RViz's and
    /// tf2's `/tf_static` subscribers are transient local and ignore a volatile one), volatile
    /// for every other topic.
    ///
    /// ```
    /// use sndt_host::dataset::ros::metadata::QosProfile;
    /// assert_eq!(QosProfile::for_topic("/tf_static").durability, QosProfile::TRANSIENT_LOCAL);
    /// assert_eq!(QosProfile::for_topic("/tf").durability, QosProfile::VOLATILE);
    /// ```
    pub fn for_topic(topic: &str) -> QosProfile {
        if topic == "/tf_static" {
            QosProfile::latched()
        } else {
            QosProfile::volatile()
        }
    }
}

/// `offered_qos_profiles` as Humble records it: a YAML list of profiles in one string
/// (the MCAP channel's metadata value and the `metadata.yaml` field).
pub fn serialize_qos(profiles: &[QosProfile]) -> Result<String> {
    let text = yaml_serde::to_string(profiles).context("writing QoS profiles as YAML")?;
    // yaml-cpp, which rosbag2 uses, ends the document without a newline.
    Ok(text.trim_end().to_string())
}

impl BagInfo {
    /// The description of a bag of one MCAP file, `file` (relative to the folder), as Humble
    /// writes it: `topics` with their counts, messages from `start` to `end` (ns; both 0
    /// for none).
    pub fn single_mcap(
        file: &str,
        topics: Vec<TopicWithMessageCount>,
        (start, end): (u64, u64),
    ) -> BagInfo {
        let message_count = topics.iter().map(|t| t.message_count).sum();
        let duration = Duration {
            nanoseconds: end.saturating_sub(start),
        };
        let starting_time = StartingTime {
            nanoseconds_since_epoch: start,
        };
        BagInfo {
            version: HUMBLE_VERSION,
            storage_identifier: "mcap".into(),
            duration,
            starting_time,
            message_count,
            topics_with_message_count: topics,
            compression_format: String::new(),
            compression_mode: String::new(),
            relative_file_paths: vec![file.into()],
            files: vec![FileInfo {
                path: file.into(),
                starting_time,
                duration,
                message_count,
            }],
            custom_data: None,
            ros_distro: None,
        }
    }
}

/// One storage file of a bag.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FileInfo {
    /// Path relative to the folder.
    pub path: String,
    /// Time of the file's first message.
    pub starting_time: StartingTime,
    /// Last message time minus the first.
    pub duration: Duration,
    /// Messages in the file.
    pub message_count: u64,
}

impl MetadataFile {
    /// The YAML text of `metadata.yaml`.
    pub fn to_yaml(&self) -> Result<String> {
        yaml_serde::to_string(self).context("writing metadata.yaml")
    }

    /// Parses the text of a `metadata.yaml`.
    pub fn from_yaml(text: &str) -> Result<MetadataFile> {
        yaml_serde::from_str(text).context("not a rosbag2 metadata.yaml")
    }

    /// Reads `dir/metadata.yaml`.
    pub fn read(dir: &Path) -> Result<MetadataFile> {
        let path = dir.join(METADATA_FILE);
        if !path.is_file() {
            bail!(
                "{}: no {METADATA_FILE} (a rosbag2 bag folder has one beside its storage files)",
                dir.display()
            );
        }
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("reading {}", path.display()))?;
        MetadataFile::from_yaml(&text).with_context(|| format!("{}", path.display()))
    }
}

/// The MCAP files of the bag folder `dir`, in the order its `metadata.yaml` lists them
/// (`relative_file_paths`, the recording order of a split bag). Fails when the folder has
/// no `metadata.yaml`, stores its messages other than in MCAP files (e.g. `sqlite3`), has
/// rosbag2 compress whole files or messages, or lacks a listed file.
pub fn bag_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let info = MetadataFile::read(dir)?.rosbag2_bagfile_information;
    let shown = dir.join(METADATA_FILE);
    let shown = shown.display();
    if info.storage_identifier != "mcap" {
        bail!(
            "{shown}: storage `{}`: only MCAP bags are supported (`ros2 bag record -s mcap`, \
             or `ros2 bag convert` the bag to MCAP)",
            info.storage_identifier
        );
    }
    if !matches!(info.compression_mode.as_str(), "" | "none" | "None") {
        bail!(
            "{shown}: rosbag2 compressed this bag per {} ({}), which sndt cannot read; \
             `ros2 bag convert` it to an uncompressed bag",
            info.compression_mode,
            info.compression_format
        );
    }
    if info.relative_file_paths.is_empty() {
        bail!("{shown}: lists no files");
    }
    info.relative_file_paths
        .iter()
        .map(|rel| {
            let file = listed_file(dir, rel);
            if file.is_file() {
                Ok(file)
            } else {
                bail!("{shown} lists {rel}, which is missing")
            }
        })
        .collect()
}

/// A listed file's path: relative to the folder; before version 4 rosbag2 wrote paths
/// relative to the folder's parent (`bag/bag_0.db3`), so a path whose whole is missing is
/// taken by its file name.
fn listed_file(dir: &Path, rel: &str) -> PathBuf {
    let joined = dir.join(rel);
    match Path::new(rel).file_name() {
        Some(name) if !joined.exists() => dir.join(name),
        _ => joined,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `metadata.yaml` in the form rosbag2 on Humble writes it (yaml-cpp: QoS profiles as a
    /// double-quoted string, empty strings as `""`), of a bag split into two files.
    const HUMBLE: &str = r#"rosbag2_bagfile_information:
  version: 5
  storage_identifier: mcap
  duration:
    nanoseconds: 2500000000
  starting_time:
    nanoseconds_since_epoch: 1700000000000000000
  message_count: 7
  topics_with_message_count:
    - topic_metadata:
        name: /tf_static
        type: tf2_msgs/msg/TFMessage
        serialization_format: cdr
        offered_qos_profiles: "- history: 3\n  depth: 0\n  reliability: 1\n  durability: 1\n  deadline:\n    sec: 9223372036\n    nsec: 854775807\n  lifespan:\n    sec: 9223372036\n    nsec: 854775807\n  liveliness: 1\n  liveliness_lease_duration:\n    sec: 9223372036\n    nsec: 854775807\n  avoid_ros_namespace_conventions: false"
      message_count: 1
    - topic_metadata:
        name: /tf
        type: tf2_msgs/msg/TFMessage
        serialization_format: cdr
        offered_qos_profiles: ""
      message_count: 6
  compression_format: ""
  compression_mode: ""
  relative_file_paths:
    - rec_0.mcap
    - rec_1.mcap
  files:
    - path: rec_0.mcap
      starting_time:
        nanoseconds_since_epoch: 1700000000000000000
      duration:
        nanoseconds: 1000000000
      message_count: 4
    - path: rec_1.mcap
      starting_time:
        nanoseconds_since_epoch: 1700000001500000000
      duration:
        nanoseconds: 1000000000
      message_count: 3
"#;

    /// The later form (version 9, as e.g. the `rosbags` library writes it): QoS as a list with
    /// enum names, and the fields of versions 6 to 8.
    const V9: &str = r"rosbag2_bagfile_information:
  version: 9
  storage_identifier: mcap
  relative_file_paths:
  - b.mcap
  duration:
    nanoseconds: 0
  starting_time:
    nanoseconds_since_epoch: 5
  message_count: 1
  topics_with_message_count:
  - topic_metadata:
      name: /tf_static
      type: tf2_msgs/msg/TFMessage
      serialization_format: cdr
      offered_qos_profiles:
      - history: keep_last
        depth: 1
        reliability: reliable
        durability: transient_local
      type_description_hash: RIHS01_e369
    message_count: 1
  compression_format: ''
  compression_mode: ''
  files:
  - path: b.mcap
    starting_time:
      nanoseconds_since_epoch: 5
    duration:
      nanoseconds: 0
    message_count: 1
  custom_data: null
  ros_distro: rosbags
";

    /// A fresh directory under the system's temporary directory.
    fn temp(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("sndt-meta-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_humble_metadata_file_reads_and_round_trips() {
        let file = MetadataFile::from_yaml(HUMBLE).unwrap();
        let info = &file.rosbag2_bagfile_information;
        assert_eq!(
            (info.version, info.storage_identifier.as_str()),
            (5, "mcap")
        );
        assert_eq!(
            info.starting_time.nanoseconds_since_epoch,
            1_700_000_000_000_000_000
        );
        assert_eq!(
            (info.duration.nanoseconds, info.message_count),
            (2_500_000_000, 7)
        );
        assert_eq!(info.relative_file_paths, ["rec_0.mcap", "rec_1.mcap"]);
        assert_eq!(info.files[1].message_count, 3);
        assert_eq!(
            info.files[1].starting_time.nanoseconds_since_epoch,
            1_700_000_001_500_000_000
        );
        let tf_static = &info.topics_with_message_count[0].topic_metadata;
        assert_eq!(tf_static.kind, "tf2_msgs/msg/TFMessage");
        let OfferedQos::Text(qos) = &tf_static.offered_qos_profiles else {
            panic!("Humble writes QoS as a string");
        };
        let profiles: Vec<QosProfile> = yaml_serde::from_str(qos).unwrap();
        assert_eq!(profiles[0].durability, QosProfile::TRANSIENT_LOCAL);
        assert_eq!(profiles[0].deadline, QosTime::INFINITE);
        assert_eq!(
            (info.custom_data.as_ref(), info.ros_distro.as_ref()),
            (None, None)
        );
        // Written again it reads back the same, and without the fields Humble lacks.
        let text = file.to_yaml().unwrap();
        assert!(!text.contains("ros_distro") && !text.contains("type_description_hash"));
        assert_eq!(MetadataFile::from_yaml(&text).unwrap(), file);
    }

    #[test]
    fn a_version_9_metadata_file_reads_and_round_trips() {
        let file = MetadataFile::from_yaml(V9).unwrap();
        let info = &file.rosbag2_bagfile_information;
        assert_eq!(
            (info.version, info.ros_distro.as_deref()),
            (9, Some("rosbags"))
        );
        let topic = &info.topics_with_message_count[0].topic_metadata;
        assert_eq!(topic.type_description_hash.as_deref(), Some("RIHS01_e369"));
        let OfferedQos::List(list) = &topic.offered_qos_profiles else {
            panic!("version 9 writes QoS as a list");
        };
        assert_eq!(list[0]["durability"].as_str(), Some("transient_local"));
        let text = file.to_yaml().unwrap();
        assert_eq!(MetadataFile::from_yaml(&text).unwrap(), file);
    }

    #[test]
    fn qos_profiles_serialize_as_humble_records_them() {
        // rosbag2_transport's encoding: rmw enum values in rmw's field order, durations as
        // sec/nsec, RMW_DURATION_INFINITE for defaults; no newline at the end.
        let expected = "- history: 1\n  depth: 1\n  reliability: 1\n  durability: 1\n  \
            deadline:\n    sec: 9223372036\n    nsec: 854775807\n  \
            lifespan:\n    sec: 9223372036\n    nsec: 854775807\n  liveliness: 1\n  \
            liveliness_lease_duration:\n    sec: 9223372036\n    nsec: 854775807\n  \
            avoid_ros_namespace_conventions: false";
        assert_eq!(serialize_qos(&[QosProfile::latched()]).unwrap(), expected);
        let volatile = serialize_qos(&[QosProfile::for_topic("/camera/image")]).unwrap();
        assert!(volatile.contains("  depth: 10\n  reliability: 1\n  durability: 2\n"));
    }

    #[test]
    fn a_single_mcap_bag_states_its_file_span_and_counts() {
        let topic = |name: &str, n| TopicWithMessageCount {
            topic_metadata: TopicMetadata {
                name: name.into(),
                kind: "tf2_msgs/msg/TFMessage".into(),
                serialization_format: "cdr".into(),
                offered_qos_profiles: OfferedQos::default(),
                type_description_hash: None,
            },
            message_count: n,
        };
        let info = BagInfo::single_mcap(
            "b_0.mcap",
            vec![topic("/tf", 4), topic("/tf_static", 1)],
            (10, 35),
        );
        assert_eq!(
            (info.version, info.message_count, info.duration.nanoseconds),
            (5, 5, 25)
        );
        assert_eq!(info.relative_file_paths, ["b_0.mcap"]);
        assert_eq!(info.files[0].path, "b_0.mcap");
        assert_eq!(info.files[0].starting_time.nanoseconds_since_epoch, 10);
        assert_eq!(
            (
                info.files[0].message_count,
                info.files[0].duration.nanoseconds
            ),
            (5, 25)
        );
    }

    #[test]
    fn bag_files_follow_the_listed_order() {
        let dir = temp("order");
        // Listed out of name order, and one path in the pre-version-4 form (folder/file).
        let text = HUMBLE.replace(
            "    - rec_0.mcap\n    - rec_1.mcap",
            "    - rec_1.mcap\n    - order/rec_0.mcap",
        );
        std::fs::write(dir.join("metadata.yaml"), text).unwrap();
        for f in ["rec_0.mcap", "rec_1.mcap"] {
            std::fs::write(dir.join(f), b"").unwrap();
        }
        let files = bag_files(&dir).unwrap();
        assert_eq!(files, [dir.join("rec_1.mcap"), dir.join("rec_0.mcap")]);
    }

    #[test]
    fn bag_files_explain_what_is_wrong() {
        let err = |dir: &Path| format!("{:#}", bag_files(dir).unwrap_err());
        let dir = temp("errors");
        assert!(err(&dir).contains("no metadata.yaml"), "{}", err(&dir));
        std::fs::write(
            dir.join("metadata.yaml"),
            HUMBLE.replace("storage_identifier: mcap", "storage_identifier: sqlite3"),
        )
        .unwrap();
        assert!(
            err(&dir).contains("storage `sqlite3`: only MCAP bags are supported"),
            "{}",
            err(&dir)
        );
        std::fs::write(dir.join("metadata.yaml"), HUMBLE).unwrap();
        std::fs::write(dir.join("rec_0.mcap"), b"").unwrap();
        assert!(
            err(&dir).ends_with("lists rec_1.mcap, which is missing"),
            "{}",
            err(&dir)
        );
        std::fs::write(
            dir.join("metadata.yaml"),
            HUMBLE.replace("compression_mode: \"\"", "compression_mode: file"),
        )
        .unwrap();
        assert!(
            err(&dir).contains("compressed this bag per file"),
            "{}",
            err(&dir)
        );
        std::fs::write(
            dir.join("metadata.yaml"),
            "rosbag2_bagfile_information: 3\n",
        )
        .unwrap();
        assert!(
            err(&dir).contains("not a rosbag2 metadata.yaml"),
            "{}",
            err(&dir)
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
