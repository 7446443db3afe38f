//! A map as ROS 2 messages in an MCAP file that Foxglove opens and `ros2 bag play` plays:
//! the occupied Gaussians' means as a `sensor_msgs/msg/PointCloud2` (x, y, z, rgb in the
//! NYU40 palette, class, confidence, occupancy) and as ellipsoid markers
//! (`visualization_msgs/msg/MarkerArray`), and the occupancy layer as an OctoMap binary tree
//! (`octomap_msgs/msg/Octomap` on `/octomap_binary`, as octomap_server publishes it, see
//! [`crate::output::octomap`]), in the frame `sndt_map`, which `/tf_static` puts at the
//! identity of the world frame. Written once, or every N frames
//! (`--mcap-interval N`) so that the recording plays back as a growing map.

use super::write::BagWriter;
use crate::dataset::classes::color;
use crate::dataset::ros::msgs::{
    self, ColorRgba, Header, Marker, MarkerArray, Octomap, PointCloud2, PointField, Pose,
    TfMessage, Time, Transform, TransformStamped,
};
use crate::output::octomap::OctoMap;
use anyhow::Result;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion};
use sndt_core::{Map, Occupancy};
use std::path::Path;

/// Topic of the point cloud.
pub const POINTS: &str = "/sndt/map/points";
/// Topic of the ellipsoid markers.
pub const GAUSSIANS: &str = "/sndt/map/gaussians";
/// Topic of the OctoMap binary tree (octomap_server's name for it).
pub const OCTOMAP: &str = "/octomap_binary";
/// Frame of the map's messages.
pub const MAP_FRAME: &str = "sndt_map";

/// Bytes per point of the cloud: x, y, z, rgb, confidence, occupancy (f32), class (u8),
/// padding to 28.
pub const POINT_STEP: u32 = 28;

/// The cloud's fields: `(name, offset, datatype)` (7 FLOAT32, 2 UINT8).
pub const FIELDS: [(&str, u32, u8); 7] = [
    ("x", 0, 7),
    ("y", 4, 7),
    ("z", 8, 7),
    ("rgb", 12, 7),
    ("confidence", 16, 7),
    ("occupancy", 20, 7),
    ("class", 24, 2),
];

/// One exported voxel.
struct Exported {
    mean: [f32; 3],
    covariance: Matrix3<f64>,
    class: u8,
    confidence: f32,
    occupancy: f32,
}

/// The occupied voxels with at least `min_points` points, in the map's canonical order.
fn exported<const V: usize, const B: usize, const C: usize>(
    map: &Map<V, B, C>,
    min_points: u32,
) -> Vec<Exported> {
    map.voxels()
        .filter(|v| v.occupancy() == Occupancy::Occupied && v.gaussian.count >= min_points)
        .map(|v| {
            let (class, confidence) = v.class().unwrap_or((0, 0.0));
            let m = v.gaussian.mean;
            Exported {
                mean: [m.x, m.y, m.z],
                covariance: v.gaussian.covariance.cast::<f64>(),
                class,
                confidence,
                occupancy: 1.0 / (1.0 + (-v.log_odds).exp()),
            }
        })
        .collect()
}

/// The NYU40 colour of a class packed as PCL does (`0x00RRGGBB` in the bits of an f32).
fn packed_rgb(class: u8) -> f32 {
    let [r, g, b] = color(class);
    f32::from_bits(u32::from(r) << 16 | u32::from(g) << 8 | u32::from(b))
}

/// The cloud of the exported voxels.
fn cloud(header: Header, voxels: &[Exported]) -> PointCloud2 {
    let mut data = Vec::with_capacity(voxels.len() * POINT_STEP as usize);
    for v in voxels {
        for x in [
            v.mean[0],
            v.mean[1],
            v.mean[2],
            packed_rgb(v.class),
            v.confidence,
            v.occupancy,
        ] {
            data.extend_from_slice(&x.to_le_bytes());
        }
        data.extend_from_slice(&[v.class, 0, 0, 0]);
    }
    PointCloud2 {
        header,
        height: 1,
        width: voxels.len() as u32,
        fields: FIELDS
            .iter()
            .map(|&(name, offset, datatype)| PointField {
                name: name.into(),
                offset,
                datatype,
                count: 1,
            })
            .collect(),
        is_bigendian: false,
        point_step: POINT_STEP,
        row_step: POINT_STEP * voxels.len() as u32,
        data,
        is_dense: true,
    }
}

/// A sphere marker scaled and turned to a Gaussian's ellipsoid at `sigmas` standard
/// deviations (eigenvalues floored at (1 mm)^2 so flat Gaussians stay visible).
fn ellipsoid(header: &Header, id: i32, v: &Exported, sigmas: f64) -> Marker {
    let eig = v.covariance.symmetric_eigen();
    let mut axes = eig.eigenvectors;
    if axes.determinant() < 0.0 {
        axes.set_column(2, &(-axes.column(2)));
    }
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(axes));
    let size = |i: usize| 2.0 * sigmas * eig.eigenvalues[i].max(1e-6).sqrt();
    let [r, g, b] = color(v.class).map(|c| f32::from(c) / 255.0);
    Marker {
        header: header.clone(),
        ns: "sndt".into(),
        id,
        kind: 2,
        action: 0,
        pose: Pose {
            position: msgs::Point {
                x: v.mean[0].into(),
                y: v.mean[1].into(),
                z: v.mean[2].into(),
            },
            orientation: msgs::Quaternion {
                x: q.i,
                y: q.j,
                z: q.k,
                w: q.w,
            },
        },
        scale: msgs::Vector3 {
            x: size(0),
            y: size(1),
            z: size(2),
        },
        color: ColorRgba { r, g, b, a: 1.0 },
        ..Marker::default()
    }
}

/// The markers of the exported voxels, after one that deletes the previous ones (so a
/// growing map replaces itself in a viewer).
fn markers(header: Header, voxels: &[Exported], sigmas: f64) -> MarkerArray {
    let clear = Marker {
        header: header.clone(),
        ns: "sndt".into(),
        action: 3,
        ..Marker::default()
    };
    let shapes = voxels
        .iter()
        .enumerate()
        .map(|(i, v)| ellipsoid(&header, i as i32, v, sigmas));
    MarkerArray {
        markers: std::iter::once(clear).chain(shapes).collect(),
    }
}

/// The occupancy layer of `map` as the binary `OcTree` message octomap_server publishes.
fn octomap<const V: usize, const B: usize, const C: usize>(
    header: Header,
    map: &Map<V, B, C>,
) -> Octomap {
    let tree = OctoMap::from_map(map);
    Octomap {
        header,
        binary: true,
        id: "OcTree".into(),
        resolution: tree.resolution(),
        data: tree.binary_data().bytes,
    }
}

/// An MCAP file of map snapshots.
pub struct MapBag {
    bag: BagWriter,
    /// Ellipsoids at this many standard deviations.
    pub sigmas: f64,
    /// Only voxels with at least this many points.
    pub min_points: u32,
    /// Snapshots written.
    pub written: usize,
}

impl MapBag {
    /// Creates `path` with the map's topics and `/tf_static` placing `sndt_map` at the
    /// identity of `world_frame`.
    pub fn create(path: &Path, world_frame: &str, stamp: Time) -> Result<MapBag> {
        let mut bag = BagWriter::create(path)?;
        bag.add_topic(POINTS, msgs::definitions::point_cloud2())?;
        bag.add_topic(GAUSSIANS, msgs::definitions::marker_array())?;
        bag.add_topic(OCTOMAP, msgs::definitions::octomap())?;
        bag.add_topic("/tf_static", msgs::definitions::tf_message())?;
        let fixed = TransformStamped {
            header: Header {
                stamp,
                frame_id: world_frame.into(),
            },
            child_frame_id: MAP_FRAME.into(),
            transform: Transform::default(),
        };
        bag.write(
            "/tf_static",
            stamp,
            &TfMessage {
                transforms: vec![fixed],
            },
        )?;
        Ok(MapBag {
            bag,
            sigmas: 2.0,
            min_points: 3,
            written: 0,
        })
    }

    /// Writes the map as it is at `stamp`: the cloud, the markers and the OctoMap. Returns
    /// the points.
    pub fn write<const V: usize, const B: usize, const C: usize>(
        &mut self,
        map: &Map<V, B, C>,
        stamp: Time,
    ) -> Result<usize> {
        let voxels = exported(map, self.min_points);
        let header = Header {
            stamp,
            frame_id: MAP_FRAME.into(),
        };
        self.bag
            .write(POINTS, stamp, &cloud(header.clone(), &voxels))?;
        self.bag.write(
            GAUSSIANS,
            stamp,
            &markers(header.clone(), &voxels, self.sigmas),
        )?;
        self.bag.write(OCTOMAP, stamp, &octomap(header, map))?;
        self.written += 1;
        Ok(voxels.len())
    }

    /// Finishes the file.
    pub fn finish(self) -> Result<()> {
        self.bag.finish()
    }
}
