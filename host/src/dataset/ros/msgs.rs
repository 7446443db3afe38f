//! The ROS 2 messages sndt reads and writes, as serde structs in the field order of their
//! `.msg` definitions (CDR encodes fields in order, so the order is the format), and the
//! definition texts that go into MCAP schema records (`ros2msg` encoding).

use serde::{Deserialize, Serialize};

/// Encodes a message as ROS 2 publishes it: the encapsulation header of little-endian plain
/// CDR, then the fields in order.
///
/// ```
/// use sndt_host::dataset::ros::msgs::{from_cdr, to_cdr, Time};
/// let t = Time { sec: 7, nanosec: 9 };
/// assert_eq!(to_cdr(&t).unwrap(), [0, 1, 0, 0, 7, 0, 0, 0, 9, 0, 0, 0]);
/// assert_eq!(from_cdr::<Time>(&to_cdr(&t).unwrap()), Ok(t));
/// ```
pub fn to_cdr<T: Serialize>(msg: &T) -> Result<Vec<u8>, String> {
    let body =
        cdr_encoding::to_vec::<T, byteorder::LittleEndian>(msg).map_err(|e| e.to_string())?;
    let mut out = Vec::with_capacity(4 + body.len());
    out.extend_from_slice(&[0, 1, 0, 0]);
    out.extend_from_slice(&body);
    Ok(out)
}

/// Decodes a CDR message: the 4-byte encapsulation header (plain CDR, big- or
/// little-endian), then the fields. Each declared string or sequence length is checked
/// against the bytes left before anything is copied, so a corrupt length is an error, not
/// an allocation of up to 4 GiB.
///
/// ```
/// use sndt_host::dataset::ros::msgs::{from_cdr, Time};
/// let le = [0, 1, 0, 0, 7, 0, 0, 0, 9, 0, 0, 0];
/// assert_eq!(from_cdr::<Time>(&le), Ok(Time { sec: 7, nanosec: 9 }));
/// // A string claiming 4 GiB in a 12-byte message.
/// let bad = [0, 1, 0, 0, 0xff, 0xff, 0xff, 0xff, b'a', 0, 0, 0];
/// assert!(from_cdr::<String>(&bad).is_err());
/// ```
pub fn from_cdr<T: serde::de::DeserializeOwned>(data: &[u8]) -> Result<T, String> {
    use byteorder::{BigEndian, LittleEndian};
    let (Some(header), Some(body)) = (data.get(..4), data.get(4..)) else {
        return Err("shorter than its 4-byte encapsulation header".into());
    };
    let decoded = match header[1] {
        0 | 2 => cdr_encoding::from_bytes::<T, BigEndian>(body),
        1 | 3 => cdr_encoding::from_bytes::<T, LittleEndian>(body),
        other => return Err(format!("encapsulation {other:#04x} is not plain CDR")),
    };
    decoded.map(|(v, _)| v).map_err(|e| e.to_string())
}

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
    /// use sndt_host::dataset::ros::msgs::Time;
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

/// `sensor_msgs/msg/PointField`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointField {
    /// Field name.
    pub name: String,
    /// Byte offset in the point.
    pub offset: u32,
    /// 1 INT8, 2 UINT8, 3 INT16, 4 UINT16, 5 INT32, 6 UINT32, 7 FLOAT32, 8 FLOAT64.
    pub datatype: u8,
    /// Elements.
    pub count: u32,
}

/// `sensor_msgs/msg/PointCloud2`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointCloud2 {
    /// Stamp and frame of the points.
    pub header: Header,
    /// Rows (1 for an unordered cloud).
    pub height: u32,
    /// Points per row.
    pub width: u32,
    /// The fields of a point.
    pub fields: Vec<PointField>,
    /// Big-endian data.
    pub is_bigendian: bool,
    /// Bytes per point.
    pub point_step: u32,
    /// Bytes per row.
    pub row_step: u32,
    /// The points.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
    /// No invalid points.
    pub is_dense: bool,
}

/// `std_msgs/msg/ColorRGBA`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ColorRgba {
    /// Red, 0..=1.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
    /// Alpha.
    pub a: f32,
}

/// `builtin_interfaces/msg/Duration`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Duration {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds.
    pub nanosec: u32,
}

/// `sensor_msgs/msg/CompressedImage`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CompressedImage {
    /// Stamp and frame.
    pub header: Header,
    /// `jpeg`, `png`, ...
    pub format: String,
    /// The compressed bytes.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/UVCoordinate`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct UvCoordinate {
    /// u.
    pub u: f32,
    /// v.
    pub v: f32,
}

/// `visualization_msgs/msg/MeshFile`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshFile {
    /// File name.
    pub filename: String,
    /// Contents.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/Marker` (the ROS 2 Humble and later layout).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    /// Stamp and frame.
    pub header: Header,
    /// Namespace.
    pub ns: String,
    /// Id within the namespace.
    pub id: i32,
    /// 2 SPHERE, ...
    #[serde(rename = "type")]
    pub kind: i32,
    /// 0 ADD, 2 DELETE, 3 DELETEALL.
    pub action: i32,
    /// Pose of the shape.
    pub pose: Pose,
    /// Size along the shape's axes, metres.
    pub scale: Vector3,
    /// Colour.
    pub color: ColorRgba,
    /// 0: forever.
    pub lifetime: Duration,
    /// Follow the frame.
    pub frame_locked: bool,
    /// Points of list shapes.
    pub points: Vec<Point>,
    /// Colours of list shapes.
    pub colors: Vec<ColorRgba>,
    /// Texture resource.
    pub texture_resource: String,
    /// Texture.
    pub texture: CompressedImage,
    /// Texture coordinates.
    pub uv_coordinates: Vec<UvCoordinate>,
    /// Text of text markers.
    pub text: String,
    /// Mesh resource.
    pub mesh_resource: String,
    /// Mesh file.
    pub mesh_file: MeshFile,
    /// Use the mesh's materials.
    pub mesh_use_embedded_materials: bool,
}

/// `visualization_msgs/msg/MarkerArray`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MarkerArray {
    /// The markers.
    pub markers: Vec<Marker>,
}

/// `octomap_msgs/msg/Octomap` (octomap_msgs 2.x, the ROS 2 package): an OctoMap tree as
/// `octomap_msgs::fullMsgToMap` / `binaryMsgToMap` read it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Octomap {
    /// Stamp and the tree's frame.
    pub header: Header,
    /// True for a binary tree (free / occupied only, `.bt` data), false for a full one.
    pub binary: bool,
    /// The tree's class: `OcTree`, `ColorOcTree`, ...
    pub id: String,
    /// Edge of the smallest nodes, metres.
    pub resolution: f64,
    /// The tree as `writeBinaryData` / `writeData` write it, without the file header.
    /// `int8[]` in the message: CDR encodes it byte for byte like `uint8[]`, so the bytes
    /// are kept as they are written.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
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

    const POINT: (&str, &str) = ("geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n");
    const POSE: (&str, &str) = (
        "geometry_msgs/Pose",
        "Point position\nQuaternion orientation\n",
    );
    const COLOR: (&str, &str) = (
        "std_msgs/ColorRGBA",
        "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n",
    );
    const DURATION: (&str, &str) = ("builtin_interfaces/Duration", "int32 sec\nuint32 nanosec\n");
    const POINT_FIELD: (&str, &str) = (
        "sensor_msgs/PointField",
        "uint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\nuint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count\n",
    );
    const MARKER: (&str, &str) = (
        "visualization_msgs/Marker",
        "int32 ARROW=0\nint32 CUBE=1\nint32 SPHERE=2\nint32 CYLINDER=3\nint32 LINE_STRIP=4\nint32 LINE_LIST=5\nint32 CUBE_LIST=6\nint32 SPHERE_LIST=7\nint32 POINTS=8\nint32 TEXT_VIEW_FACING=9\nint32 MESH_RESOURCE=10\nint32 TRIANGLE_LIST=11\nint32 ADD=0\nint32 MODIFY=0\nint32 DELETE=2\nint32 DELETEALL=3\nstd_msgs/Header header\nstring ns\nint32 id\nint32 type\nint32 action\ngeometry_msgs/Pose pose\ngeometry_msgs/Vector3 scale\nstd_msgs/ColorRGBA color\nbuiltin_interfaces/Duration lifetime\nbool frame_locked\ngeometry_msgs/Point[] points\nstd_msgs/ColorRGBA[] colors\nstring texture_resource\nsensor_msgs/CompressedImage texture\nUVCoordinate[] uv_coordinates\nstring text\nstring mesh_resource\nMeshFile mesh_file\nbool mesh_use_embedded_materials\n",
    );
    const COMPRESSED: (&str, &str) = (
        "sensor_msgs/CompressedImage",
        "std_msgs/Header header\nstring format\nuint8[] data\n",
    );
    const UV: (&str, &str) = ("visualization_msgs/UVCoordinate", "float32 u\nfloat32 v\n");
    const MESH_FILE: (&str, &str) = (
        "visualization_msgs/MeshFile",
        "string filename\nuint8[] data\n",
    );

    /// `geometry_msgs/msg/PoseStamped`.
    pub fn pose_stamped() -> (&'static str, String) {
        let own = "std_msgs/Header header\nPose pose\n";
        (
            "geometry_msgs/msg/PoseStamped",
            with_deps(own, &[HEADER, TIME, POSE, POINT, QUATERNION]),
        )
    }

    /// `nav_msgs/msg/Odometry`.
    pub fn odometry() -> (&'static str, String) {
        let own = "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist\n";
        let deps = [
            HEADER,
            TIME,
            (
                "geometry_msgs/PoseWithCovariance",
                "Pose pose\nfloat64[36] covariance\n",
            ),
            POSE,
            POINT,
            QUATERNION,
            (
                "geometry_msgs/TwistWithCovariance",
                "Twist twist\nfloat64[36] covariance\n",
            ),
            ("geometry_msgs/Twist", "Vector3 linear\nVector3 angular\n"),
            VECTOR3,
        ];
        ("nav_msgs/msg/Odometry", with_deps(own, &deps))
    }

    /// `sensor_msgs/msg/PointCloud2`.
    pub fn point_cloud2() -> (&'static str, String) {
        let own = "std_msgs/Header header\nuint32 height\nuint32 width\nPointField[] fields\nbool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n";
        (
            "sensor_msgs/msg/PointCloud2",
            with_deps(own, &[HEADER, TIME, POINT_FIELD]),
        )
    }

    /// `visualization_msgs/msg/MarkerArray`.
    pub fn marker_array() -> (&'static str, String) {
        let own = "Marker[] markers\n";
        let deps = [
            MARKER, HEADER, TIME, POSE, POINT, QUATERNION, VECTOR3, COLOR, DURATION, COMPRESSED,
            UV, MESH_FILE,
        ];
        ("visualization_msgs/msg/MarkerArray", with_deps(own, &deps))
    }

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

    /// `octomap_msgs/msg/Octomap`: the text of `msg/Octomap.msg` in octomap_msgs 2.0.0 (the
    /// ROS 2 Humble package), comments included.
    pub fn octomap() -> (&'static str, String) {
        let own = "# A 3D map in binary format, as Octree\nstd_msgs/Header header\n\n# Flag to denote a binary (only free/occupied) or full occupancy octree (.bt/.ot file)\nbool binary\n\n# Class id of the contained octree \nstring id\n\n# Resolution (in m) of the smallest octree nodes\nfloat64 resolution\n\n# binary serialization of octree, use conversions.h to read and write octrees\nint8[] data\n";
        ("octomap_msgs/msg/Octomap", with_deps(own, &[HEADER, TIME]))
    }
}
