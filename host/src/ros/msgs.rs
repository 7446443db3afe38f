//! The ROS 2 messages sndt reads and writes, as serde structs in the field order of their
//! `.msg` definitions (CDR encodes fields in order, so the order is the format), and the
//! definition texts that go into MCAP schema records (`ros2msg` encoding).

use serde::{Deserialize, Serialize};

/// `builtin_interfaces/msg/Time`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds, 0..1e9.
    pub nanosec: u32,
}

impl Time {
    /// From nanoseconds since the epoch (as MCAP log times).
    ///
    /// ```
    /// use sndt_host::ros::msgs::Time;
    /// assert_eq!(Time::from_nanos(1_500_000_000), Time { sec: 1, nanosec: 500_000_000 });
    /// assert_eq!(Time::from_nanos(1_500_000_000).nanos(), 1_500_000_000);
    /// ```
    pub fn from_nanos(ns: u64) -> Time {
        Time {
            sec: (ns / 1_000_000_000) as i32,
            nanosec: (ns % 1_000_000_000) as u32,
        }
    }

    /// Nanoseconds since the epoch (negative times clamp to 0).
    pub fn nanos(&self) -> u64 {
        (self.sec.max(0) as u64) * 1_000_000_000 + self.nanosec as u64
    }
}

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// Acquisition time.
    pub stamp: Time,
    /// Coordinate frame of the data.
    pub frame_id: String,
}

/// `sensor_msgs/msg/Image`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Image {
    /// Stamp and camera frame.
    pub header: Header,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// Pixel encoding: `16UC1`, `32FC1`, `mono8`, `8UC1`, ...
    pub encoding: String,
    /// 1 when multi-byte values are big-endian.
    pub is_bigendian: u8,
    /// Bytes per row.
    pub step: u32,
    /// `step * height` bytes.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}

/// `sensor_msgs/msg/RegionOfInterest`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RegionOfInterest {
    /// Left column.
    pub x_offset: u32,
    /// Top row.
    pub y_offset: u32,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// Whether the region was rectified.
    pub do_rectify: bool,
}

/// `sensor_msgs/msg/CameraInfo`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CameraInfo {
    /// Stamp and camera frame.
    pub header: Header,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// `plumb_bob`, `rational_polynomial`, `equidistant` or empty.
    pub distortion_model: String,
    /// Distortion coefficients.
    pub d: Vec<f64>,
    /// Intrinsics of the raw image, row-major 3x3.
    pub k: [f64; 9],
    /// Rectification rotation, row-major 3x3.
    pub r: [f64; 9],
    /// Projection of the rectified image, row-major 3x4.
    pub p: [f64; 12],
    /// Binning in x.
    pub binning_x: u32,
    /// Binning in y.
    pub binning_y: u32,
    /// Region of interest.
    pub roi: RegionOfInterest,
}

/// `geometry_msgs/msg/Vector3`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion` (x, y, z, w).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

/// `geometry_msgs/msg/Transform`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    /// Translation, metres.
    pub translation: Vector3,
    /// Rotation.
    pub rotation: Quaternion,
}

/// `geometry_msgs/msg/TransformStamped`: the pose of `child_frame_id` in `header.frame_id`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TransformStamped {
    /// Stamp and parent frame.
    pub header: Header,
    /// Child frame.
    pub child_frame_id: String,
    /// Child-to-parent transform.
    pub transform: Transform,
}

/// `tf2_msgs/msg/TFMessage`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TfMessage {
    /// Transforms.
    pub transforms: Vec<TransformStamped>,
}

/// `geometry_msgs/msg/Point`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `geometry_msgs/msg/Pose`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Position.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

/// `geometry_msgs/msg/PoseStamped`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseStamped {
    /// Stamp and frame the pose is in.
    pub header: Header,
    /// The pose.
    pub pose: Pose,
}

/// `geometry_msgs/msg/PoseWithCovariance`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PoseWithCovariance {
    /// The pose.
    pub pose: Pose,
    /// Row-major 6x6 covariance.
    pub covariance: [[f64; 6]; 6],
}

/// `geometry_msgs/msg/Twist`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Twist {
    /// Linear velocity.
    pub linear: Vector3,
    /// Angular velocity.
    pub angular: Vector3,
}

/// `geometry_msgs/msg/TwistWithCovariance`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TwistWithCovariance {
    /// The twist.
    pub twist: Twist,
    /// Row-major 6x6 covariance.
    pub covariance: [[f64; 6]; 6],
}

/// `nav_msgs/msg/Odometry`: the pose of `child_frame_id` in `header.frame_id`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Odometry {
    /// Stamp and parent frame.
    pub header: Header,
    /// The body frame.
    pub child_frame_id: String,
    /// Pose in the parent frame.
    pub pose: PoseWithCovariance,
    /// Velocity in the child frame.
    pub twist: TwistWithCovariance,
}

/// The `ros2msg` definitions: `(schema name, full text with its dependencies)`.
pub mod definitions {
    const SEP: &str =
        "\n================================================================================\n";

    /// Joins a message's own fields with its dependencies' definitions.
    fn with_deps(own: &str, deps: &[(&str, &str)]) -> String {
        let mut s = own.to_string();
        for (name, text) in deps {
            s.push_str(SEP);
            s.push_str("MSG: ");
            s.push_str(name);
            s.push('\n');
            s.push_str(text);
        }
        s
    }

    const TIME: (&str, &str) = ("builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n");
    const HEADER: (&str, &str) = (
        "std_msgs/Header",
        "builtin_interfaces/Time stamp\nstring frame_id\n",
    );
    const VECTOR3: (&str, &str) = ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n");
    const QUATERNION: (&str, &str) = (
        "geometry_msgs/Quaternion",
        "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    );
    const TRANSFORM: (&str, &str) = (
        "geometry_msgs/Transform",
        "Vector3 translation\nQuaternion rotation\n",
    );
    const TRANSFORM_STAMPED: (&str, &str) = (
        "geometry_msgs/TransformStamped",
        "std_msgs/Header header\nstring child_frame_id\nTransform transform\n",
    );
    const ROI: (&str, &str) = (
        "sensor_msgs/RegionOfInterest",
        "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n",
    );

    /// `sensor_msgs/msg/Image`.
    pub fn image() -> (&'static str, String) {
        let own = "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data\n";
        ("sensor_msgs/msg/Image", with_deps(own, &[HEADER, TIME]))
    }

    /// `sensor_msgs/msg/CameraInfo`.
    pub fn camera_info() -> (&'static str, String) {
        let own = "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\nRegionOfInterest roi\n";
        (
            "sensor_msgs/msg/CameraInfo",
            with_deps(own, &[HEADER, TIME, ROI]),
        )
    }

    /// `tf2_msgs/msg/TFMessage`.
    pub fn tf_message() -> (&'static str, String) {
        let own = "geometry_msgs/TransformStamped[] transforms\n";
        let deps = [
            TRANSFORM_STAMPED,
            HEADER,
            TIME,
            TRANSFORM,
            VECTOR3,
            QUATERNION,
        ];
        ("tf2_msgs/msg/TFMessage", with_deps(own, &deps))
    }
}
