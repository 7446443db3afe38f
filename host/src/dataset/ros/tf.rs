//! A transform buffer as tf2 keeps one: per child frame its parent and its transforms over
//! time (`/tf`) or a fixed one (`/tf_static`); a lookup chains them from a frame up to the
//! world frame, interpolating each hop at the stamp (translation linearly, rotation by
//! slerp).

use super::msgs::{Transform, TransformStamped};
use super::stamp_text;
use anyhow::{bail, Result};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use std::collections::{BTreeSet, HashMap};

/// Largest deviation of a transform's quaternion norm from 1.
pub const QUAT_NORM_TOLERANCE: f64 = 1e-3;

/// Most hops a lookup follows (a longer chain is a cycle).
const MAX_HOPS: usize = 64;

/// Transforms by child frame.
#[derive(Clone, Debug, Default)]
pub struct TfBuffer {
    /// Child -> (parent, transform) from `/tf_static`.
    fixed: HashMap<String, (String, Transform)>,
    /// Child -> parent and the (stamp ns, transform) samples from `/tf`, sorted by stamp.
    moving: HashMap<String, (String, Vec<(u64, Transform)>)>,
}

impl TfBuffer {
    /// Adds the transforms of a `/tf` (`fixed` false) or `/tf_static` message. A child that
    /// changes parent keeps its first parent (tf2 warns about the same); returns how many
    /// transforms were ignored for that reason.
    pub fn add(&mut self, transforms: &[TransformStamped], fixed: bool) -> usize {
        let mut ignored = 0;
        for t in transforms {
            let parent = &t.header.frame_id;
            if fixed {
                self.fixed
                    .insert(t.child_frame_id.clone(), (parent.clone(), t.transform));
                continue;
            }
            let entry = self
                .moving
                .entry(t.child_frame_id.clone())
                .or_insert_with(|| (parent.clone(), Vec::new()));
            if entry.0 == *parent {
                entry.1.push((t.header.stamp.nanos(), t.transform));
            } else {
                ignored += 1;
            }
        }
        ignored
    }

    /// Sorts the samples by stamp (call once after adding).
    pub fn finish(&mut self) {
        for (_, samples) in self.moving.values_mut() {
            samples.sort_by_key(|s| s.0);
        }
    }

    /// Every frame named in the tree, as child or parent.
    pub fn frames(&self) -> BTreeSet<String> {
        let fixed = self.fixed.iter().map(|(c, (p, _))| (c, p));
        let moving = self.moving.iter().map(|(c, (p, _))| (c, p));
        fixed
            .chain(moving)
            .flat_map(|(c, p)| [c.clone(), p.clone()])
            .collect()
    }

    /// The hops of the tree, sorted by child: (child, parent, `None` for a `/tf_static`
    /// hop or the number of `/tf` samples).
    pub fn edges(&self) -> Vec<(String, String, Option<usize>)> {
        let fixed = self
            .fixed
            .iter()
            .map(|(c, (p, _))| (c.clone(), p.clone(), None));
        let moving = self
            .moving
            .iter()
            .map(|(c, (p, v))| (c.clone(), p.clone(), Some(v.len())));
        let mut edges: Vec<_> = fixed.chain(moving).collect();
        edges.sort();
        edges
    }

    /// The roots of the tree: frames that are parents and have no parent themselves (the
    /// candidates for a world frame), sorted.
    ///
    /// ```
    /// use sndt_host::dataset::ros::msgs::{Header, TransformStamped};
    /// use sndt_host::dataset::ros::tf::TfBuffer;
    /// let hop = |parent: &str, child: &str| TransformStamped {
    ///     header: Header { frame_id: parent.into(), ..Default::default() },
    ///     child_frame_id: child.into(),
    ///     ..Default::default()
    /// };
    /// let mut tf = TfBuffer::default();
    /// tf.add(&[hop("odom", "base_link"), hop("base_link", "camera")], false);
    /// tf.add(&[hop("map", "odom")], true);
    /// assert_eq!(tf.roots(), ["map"]);
    /// assert_eq!(tf.frames().len(), 4);
    /// ```
    pub fn roots(&self) -> Vec<String> {
        let children: BTreeSet<&String> = self.fixed.keys().chain(self.moving.keys()).collect();
        let parents = self.fixed.values().map(|(p, _)| p);
        let parents: BTreeSet<&String> = parents
            .chain(self.moving.values().map(|(p, _)| p))
            .collect();
        parents
            .into_iter()
            .filter(|p| !children.contains(p))
            .cloned()
            .collect()
    }

    /// The pose of `frame` in `world` at `stamp` (ns), as the f64 isometry of the chain.
    pub fn lookup(&self, world: &str, frame: &str, stamp: u64) -> Result<Isometry3<f64>> {
        let mut pose = Isometry3::identity();
        let mut current = frame.to_string();
        for _ in 0..MAX_HOPS {
            if current == world {
                return Ok(pose);
            }
            let (parent, hop) = self.hop(&current, stamp)?;
            pose = isometry(&hop)? * pose;
            current = parent;
        }
        bail!(
            "transform chain from {frame} does not reach {world} within {MAX_HOPS} hops (a cycle?)"
        )
    }

    /// The transform of `child` to its parent at `stamp`.
    fn hop(&self, child: &str, stamp: u64) -> Result<(String, Transform)> {
        if let Some((parent, t)) = self.fixed.get(child) {
            return Ok((parent.clone(), *t));
        }
        let Some((parent, samples)) = self.moving.get(child) else {
            bail!("no transform from frame {child:?} to a parent (neither /tf nor /tf_static)");
        };
        let i = samples.partition_point(|s| s.0 < stamp);
        match (samples.get(i.wrapping_sub(1)), samples.get(i)) {
            (_, Some(&(t, tr))) if t == stamp => Ok((parent.clone(), tr)),
            (Some(&(t0, a)), Some(&(t1, b))) => {
                let s = (stamp - t0) as f64 / (t1 - t0) as f64;
                Ok((parent.clone(), interpolate(&a, &b, s)?))
            }
            _ => {
                let (first, last) = (samples[0].0, samples[samples.len() - 1].0);
                bail!(
                    "no transform {parent} <- {child} at {} s: /tf has it from {} to {} s",
                    stamp_text(stamp),
                    stamp_text(first),
                    stamp_text(last)
                )
            }
        }
    }
}

/// The unit quaternion of a transform, checked.
fn rotation(t: &Transform) -> Result<UnitQuaternion<f64>> {
    let r = t.rotation;
    let q = Quaternion::new(r.w, r.x, r.y, r.z);
    let v = [
        r.w,
        r.x,
        r.y,
        r.z,
        t.translation.x,
        t.translation.y,
        t.translation.z,
    ];
    if v.iter().any(|x| !x.is_finite()) || (q.norm() - 1.0).abs() > QUAT_NORM_TOLERANCE {
        bail!("invalid transform {t:?}: not finite or not a unit quaternion");
    }
    Ok(UnitQuaternion::new_unchecked(q))
}

/// The isometry of a transform (child to parent).
fn isometry(t: &Transform) -> Result<Isometry3<f64>> {
    let v = t.translation;
    Ok(Isometry3::from_parts(
        Translation3::new(v.x, v.y, v.z),
        rotation(t)?,
    ))
}

/// `a` and `b` mixed at `s` in [0, 1]: translation linearly, rotation by slerp.
fn interpolate(a: &Transform, b: &Transform, s: f64) -> Result<Transform> {
    let (qa, qb) = (rotation(a)?, rotation(b)?);
    let q = qa.slerp(&qb, s);
    let lerp = |x: f64, y: f64| x + (y - x) * s;
    let (ta, tb) = (a.translation, b.translation);
    Ok(Transform {
        translation: super::msgs::Vector3 {
            x: lerp(ta.x, tb.x),
            y: lerp(ta.y, tb.y),
            z: lerp(ta.z, tb.z),
        },
        rotation: super::msgs::Quaternion {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        },
    })
}

/// The camera pose sndt maps with: the f64 isometry normalised and rounded to f32 as the
/// prepared layout's extrinsics are (so the same record gives the same pose bits).
pub fn to_pose(p: &Isometry3<f64>) -> sndt_core::Isometry3<f32> {
    let q = p.rotation.into_inner();
    let q = q / q.norm();
    let t = p.translation.vector;
    sndt_core::Isometry3::from_parts(
        sndt_core::Translation3::new(t.x as f32, t.y as f32, t.z as f32),
        sndt_core::UnitQuaternion::from_quaternion(q.cast::<f32>()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::ros::msgs::{Header, Time, Vector3};

    fn tf(parent: &str, child: &str, ns: u64, x: f64, yaw: f64) -> TransformStamped {
        let (s, c) = (yaw / 2.0).sin_cos();
        TransformStamped {
            header: Header {
                stamp: Time::from_nanos(ns),
                frame_id: parent.into(),
            },
            child_frame_id: child.into(),
            transform: Transform {
                translation: Vector3 { x, y: 0.0, z: 0.0 },
                rotation: super::super::msgs::Quaternion {
                    x: 0.0,
                    y: 0.0,
                    z: s,
                    w: c,
                },
            },
        }
    }

    #[test]
    fn chains_and_interpolates_as_computed_by_hand() {
        let mut b = TfBuffer::default();
        b.add(
            &[
                tf("world", "base", 1_000, 0.0, 0.0),
                tf("world", "base", 3_000, 2.0, 1.0),
            ],
            false,
        );
        b.add(&[tf("base", "cam", 0, 0.5, 0.0)], true);
        b.finish();
        // Half way: x = 1, yaw = 0.5; the camera 0.5 m ahead along the rotated x axis.
        let p = b.lookup("world", "cam", 2_000).unwrap();
        let t = p.translation.vector;
        assert!((t.x - (1.0 + 0.5 * 0.5f64.cos())).abs() < 1e-12, "{t:?}");
        assert!((t.y - 0.5 * 0.5f64.sin()).abs() < 1e-12);
        assert!((p.rotation.angle() - 0.5).abs() < 1e-12);
        // Exact stamps give the stored transform.
        assert_eq!(
            b.lookup("world", "base", 3_000)
                .unwrap()
                .translation
                .vector
                .x,
            2.0
        );
        let e = b.lookup("world", "cam", 4_000).unwrap_err().to_string();
        assert!(e.contains("base") && e.contains("0.000004000"), "{e}");
        let e = b.lookup("world", "nowhere", 2_000).unwrap_err().to_string();
        assert!(e.contains("nowhere"), "{e}");
    }
}
