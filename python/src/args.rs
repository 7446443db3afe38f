//! Checking the arguments Python hands over: numpy arrays (dtype, shape, C order), the
//! pose and the intrinsics. Every mistake is a `TypeError` (wrong kind of value or dtype)
//! or a `ValueError` (wrong shape, order or value) naming the argument and what was
//! expected, raised before the map is touched.

use numpy::{PyArray2, PyArray3, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use sndt_core::{Isometry3, Matrix3, Pinhole, Quaternion, UnitQuaternion, Vector3};

/// `argument` as a numpy array, or a `TypeError` naming what it is instead.
pub fn array<'a, 'py>(
    argument: &'a Bound<'py, PyAny>,
    name: &str,
    expected: &str,
) -> PyResult<&'a Bound<'py, PyUntypedArray>> {
    argument.cast::<PyUntypedArray>().map_err(|_| {
        let got = argument
            .get_type()
            .name()
            .map_or_else(|_| "?".to_string(), |n| n.to_string());
        PyTypeError::new_err(format!(
            "{name} must be a numpy array of {expected}, got {got}"
        ))
    })
}

/// The dtype of `a` as numpy names it (`float64`, `uint16`, ...).
pub fn dtype_name(a: &Bound<'_, PyUntypedArray>) -> String {
    a.dtype().to_string()
}

/// A `ValueError` unless `a` is C-contiguous (read in place, without a copy).
pub fn c_order(a: &Bound<'_, PyUntypedArray>, name: &str) -> PyResult<()> {
    if a.is_c_contiguous() {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "{name} must be C-contiguous (it is read in place); pass numpy.ascontiguousarray({name})"
        )))
    }
}

/// A `ValueError` unless `a` has shape `shape` (`None`: any length on that axis).
pub fn shape(a: &Bound<'_, PyUntypedArray>, name: &str, shape: &[Option<usize>]) -> PyResult<()> {
    let got = a.shape();
    let fits = got.len() == shape.len()
        && got
            .iter()
            .zip(shape)
            .all(|(g, s)| s.is_none_or(|s| s == *g));
    if fits {
        return Ok(());
    }
    let want: Vec<String> = shape
        .iter()
        .map(|s| s.map_or("N".to_string(), |s| s.to_string()))
        .collect();
    let got: Vec<String> = got.iter().map(ToString::to_string).collect();
    let comma = if got.len() == 1 { "," } else { "" };
    Err(PyValueError::new_err(format!(
        "{name} must have shape ({}), got ({}{comma})",
        want.join(", "),
        got.join(", ")
    )))
}

/// A depth image: `uint16` millimetres or `float32` metres, shape (H, W), C order.
pub enum DepthArray<'py> {
    /// Millimetres (0 = no return).
    Millimetres(numpy::PyReadonlyArray2<'py, u16>),
    /// Metres (0, negative, NaN or inf = no return).
    Metres(numpy::PyReadonlyArray2<'py, f32>),
}

impl DepthArray<'_> {
    /// (height, width).
    pub fn size(&self) -> (usize, usize) {
        let s = match self {
            DepthArray::Millimetres(a) => a.shape().to_vec(),
            DepthArray::Metres(a) => a.shape().to_vec(),
        };
        (s[0], s[1])
    }
}

/// Reads the `depth` argument.
pub fn depth<'py>(depth: &Bound<'py, PyAny>) -> PyResult<DepthArray<'py>> {
    const WHAT: &str = "uint16 millimetres or float32 metres, shape (H, W)";
    let a = array(depth, "depth", WHAT)?;
    shape(a, "depth", &[None, None])?;
    let out = if let Ok(mm) = a.cast::<PyArray2<u16>>() {
        DepthArray::Millimetres(mm.readonly())
    } else if let Ok(m) = a.cast::<PyArray2<f32>>() {
        DepthArray::Metres(m.readonly())
    } else {
        return Err(PyTypeError::new_err(format!(
            "depth must be {WHAT}, got dtype {}",
            dtype_name(a)
        )));
    };
    c_order(a, "depth")?;
    Ok(out)
}

/// Labels of a depth image.
pub enum LabelArray<'py> {
    /// No labels.
    None,
    /// One class id per pixel, `uint8` (H, W).
    Top1(numpy::PyReadonlyArray2<'py, u8>),
    /// Top-k class ids `uint8` (k, H, W) with `float32` scores in 0..1 of the same shape.
    TopK(
        numpy::PyReadonlyArray3<'py, u8>,
        numpy::PyReadonlyArray3<'py, f32>,
    ),
}

/// Reads `labels` (and `topk_scores`) for an image of `size` (height, width).
pub fn labels<'py>(
    labels: Option<&Bound<'py, PyAny>>,
    scores: Option<&Bound<'py, PyAny>>,
    size: (usize, usize),
) -> PyResult<LabelArray<'py>> {
    const WHAT: &str = "uint8 class ids, shape (H, W) or top-k (k, H, W)";
    let (h, w) = size;
    let Some(labels) = labels.filter(|l| !l.is_none()) else {
        if scores.is_some_and(|s| !s.is_none()) {
            return Err(PyValueError::new_err(
                "topk_scores given without labels: pass the top-k class ids as labels (k, H, W)",
            ));
        }
        return Ok(LabelArray::None);
    };
    let a = array(labels, "labels", WHAT)?;
    if dtype_name(a) != "uint8" {
        return Err(PyTypeError::new_err(format!(
            "labels must be {WHAT}, got dtype {}",
            dtype_name(a)
        )));
    }
    if a.ndim() == 2 {
        shape(a, "labels", &[Some(h), Some(w)])?;
        c_order(a, "labels")?;
        if scores.is_some_and(|s| !s.is_none()) {
            return Err(PyValueError::new_err(
                "topk_scores are for top-k labels of shape (k, H, W); labels have shape (H, W)",
            ));
        }
        return Ok(LabelArray::Top1(a.cast::<PyArray2<u8>>()?.readonly()));
    }
    shape(a, "labels", &[None, Some(h), Some(w)])?;
    let k = a.shape()[0];
    if !(1..=sndt_core::MAX_TOP_K).contains(&k) {
        return Err(PyValueError::new_err(format!(
            "labels of shape (k, H, W) need k in 1..={}, got k = {k}",
            sndt_core::MAX_TOP_K
        )));
    }
    c_order(a, "labels")?;
    let Some(scores) = scores.filter(|s| !s.is_none()) else {
        return Err(PyValueError::new_err(
            "top-k labels (k, H, W) need topk_scores: float32 in [0, 1] of the same shape",
        ));
    };
    let s = array(
        scores,
        "topk_scores",
        "float32 scores in [0, 1], shape (k, H, W)",
    )?;
    let Ok(typed) = s.cast::<PyArray3<f32>>() else {
        return Err(PyTypeError::new_err(format!(
            "topk_scores must be float32 scores in [0, 1], shape (k, H, W), got dtype {}",
            dtype_name(s)
        )));
    };
    shape(s, "topk_scores", &[Some(k), Some(h), Some(w)])?;
    c_order(s, "topk_scores")?;
    Ok(LabelArray::TopK(
        a.cast::<PyArray3<u8>>()?.readonly(),
        typed.readonly(),
    ))
}

/// `(fx, fy, cx, cy)` in OpenCV's convention (as ROS `CameraInfo.k`: the centre of pixel
/// `(u, v)` is at `(u, v)`) and an image size as the core's camera, whose principal point
/// counts from the pixels' corner (`+ 0.5`). Focal lengths finite and positive, centre
/// finite.
pub fn intrinsics(intrinsics: &Bound<'_, PyAny>, size: (usize, usize)) -> PyResult<Pinhole> {
    const WHAT: &str = "intrinsics must be (fx, fy, cx, cy) in pixels";
    let v: Vec<f64> = if let Ok(a) = intrinsics.cast::<PyUntypedArray>() {
        shape(a, "intrinsics", &[Some(4)])?;
        intrinsics.call_method0("tolist")?.extract()
    } else {
        intrinsics.extract()
    }
    .map_err(|_| PyTypeError::new_err(format!("{WHAT}: four numbers")))?;
    if v.len() != 4 {
        return Err(PyValueError::new_err(format!(
            "{WHAT}: four numbers, got {}",
            v.len()
        )));
    }
    if !v.iter().all(|x| x.is_finite()) || v[0] <= 0.0 || v[1] <= 0.0 {
        return Err(PyValueError::new_err(format!(
            "{WHAT}, finite, with fx and fy > 0; got {v:?}"
        )));
    }
    let (h, w) = size;
    let side = |n: usize, what: &str| {
        u32::try_from(n)
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| PyValueError::new_err(format!("image {what} {n} is not in 1..2^32")))
    };
    Ok(Pinhole {
        fx: v[0] as f32,
        fy: v[1] as f32,
        cx: (v[2] + 0.5) as f32,
        cy: (v[3] + 0.5) as f32,
        width: side(w, "width")?,
        height: side(h, "height")?,
    })
}

/// A 4x4 camera-to-world matrix (any real dtype or nested sequence): finite, last row
/// `0 0 0 1`, rotation orthonormal with determinant +1 (within 1e-3). The rotation becomes
/// a quaternion whose matrix is exactly the given one when there is one ([`exact_pose`]).
pub fn pose(pose: &Bound<'_, PyAny>) -> PyResult<Isometry3<f32>> {
    const WHAT: &str = "pose must be a 4x4 camera-to-world matrix";
    let rows: Vec<Vec<f64>> = if let Ok(a) = pose.cast::<PyUntypedArray>() {
        shape(a, "pose", &[Some(4), Some(4)])?;
        pose.call_method0("tolist")?.extract()
    } else {
        pose.extract()
    }
    .map_err(|_| PyTypeError::new_err(format!("{WHAT} of numbers")))?;
    if rows.len() != 4 || rows.iter().any(|r| r.len() != 4) {
        return Err(PyValueError::new_err(format!(
            "{WHAT}: 4 rows of 4 numbers"
        )));
    }
    if rows.iter().flatten().any(|x| !x.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "{WHAT} of finite numbers; it holds NaN or inf"
        )));
    }
    let last = &rows[3];
    if last[..3].iter().any(|x| x.abs() > 1e-6) || (last[3] - 1.0).abs() > 1e-6 {
        return Err(PyValueError::new_err(format!(
            "{WHAT}: its last row must be [0, 0, 0, 1], got {last:?}"
        )));
    }
    let r = Matrix3::from_fn(|i, j| rows[i][j] as f32);
    let t = Vector3::new(rows[0][3] as f32, rows[1][3] as f32, rows[2][3] as f32);
    exact_pose(&r, &t).map_err(|_| {
        crate::errors::PoseError::new_err(
            "pose: the rotation (upper-left 3x3) is not orthonormal with determinant +1 \
             (within 1e-3)",
        )
    })
}

/// The pose of rotation `r` and translation `t` ([`sndt_core::pose_from_matrix`]), with
/// the quaternion moved to one whose rotation matrix is `r` bit for bit when one is near.
///
/// The map uses a pose through its rotation matrix. A dataset frame holds its rotation as
/// a quaternion and Python sees that quaternion's matrix; the quaternion converted back
/// from the matrix often differs in its last bits, and then so does its matrix, which
/// changes the map in the last bits of a few voxels. So the quaternion is searched near the
/// converted one ([`search_quaternion`]). Measured on 20,000 random rotations, a quarter of
/// them near axis-aligned ones: the plain conversion is exact for 54 %, the search for
/// 99.98 % (92 % when the quaternions' norms are off by up to 5e-7, as those converted
/// from slightly skewed matrices are), in 30 us on average and 16 ms at worst. When it
/// finds none, the converted quaternion is used: the same rotation to float precision.
pub fn exact_pose(r: &Matrix3<f32>, t: &Vector3<f32>) -> Result<Isometry3<f32>, sndt_core::Error> {
    let pose = sndt_core::pose_from_matrix(r, t)?;
    let q0 = *pose.rotation.quaternion();
    if matrix_of(&q0) == *r {
        return Ok(pose);
    }
    Ok(match search_quaternion(&q0, r) {
        Some(q) => Isometry3::from_parts(pose.translation, UnitQuaternion::new_unchecked(q)),
        None => pose,
    })
}

/// The rotation matrix of `q`, as the map computes it.
fn matrix_of(q: &Quaternion<f32>) -> Matrix3<f32> {
    *UnitQuaternion::new_unchecked(*q)
        .to_rotation_matrix()
        .matrix()
}

/// `x` and `n` steps either side, each one unit in the last place of `x` or `min_step`,
/// whichever is larger.
fn around(x: f32, n: i32, min_step: f32) -> impl Iterator<Item = f32> {
    let step = (x.next_up() - x).abs().max(min_step);
    std::iter::once(x).chain((1..=n).flat_map(move |k| [x + k as f32 * step, x - k as f32 * step]))
}

/// A quaternion near `q0` whose matrix is `r` exactly: first a grid of four steps either
/// side in every component (steps of 2^-26 at least, so that a small component, whose
/// unit in the last place is much finer, still moves as far as the large ones), then the
/// smallest component scanned finely (its unit in the last place, 2^-36 at least) with
/// the others two units either side.
fn search_quaternion(q0: &Quaternion<f32>, r: &Matrix3<f32>) -> Option<Quaternion<f32>> {
    let c = q0.coords;
    let h = 2f32.powi(-26);
    let mut order = [0usize, 1, 2, 3];
    order.sort_by(|&a, &b| c[b].abs().total_cmp(&c[a].abs()));
    let [a, b, d, e] = order;
    // The first combination of one value per component (in `order`) whose matrix is `r`.
    let first = |values: [&[f32]; 4]| {
        for &va in values[0] {
            for &vb in values[1] {
                for &vd in values[2] {
                    for &ve in values[3] {
                        let mut q = *q0;
                        for (i, v) in [(a, va), (b, vb), (d, vd), (e, ve)] {
                            q.coords[i] = v;
                        }
                        if matrix_of(&q) == *r {
                            return Some(q);
                        }
                    }
                }
            }
        }
        None
    };
    let grid =
        |i: usize, n: i32, min_step: f32| -> Vec<f32> { around(c[i], n, min_step).collect() };
    let coarse = |i: usize| grid(i, 4, if c[i].abs() < 0.25 { h } else { 0.0 });
    let (ga, gb, gd, ge) = (coarse(a), coarse(b), coarse(d), coarse(e));
    if let Some(q) = first([&ga, &gb, &gd, &ge]) {
        return Some(q);
    }
    let (fa, fb, fd) = (grid(a, 2, 0.0), grid(b, 2, 0.0), grid(d, 2, 0.0));
    let steps = (2.0 * h / (h / 1024.0).max(c[e].next_up() - c[e])) as i32;
    let scan = grid(e, steps, h / 1024.0);
    first([&fa, &fb, &fd, &scan])
}

/// An (N, 3) array of points: `float32` or `float64`, any order (it is copied to `f32`).
pub fn points(points: &Bound<'_, PyAny>) -> PyResult<Vec<[f32; 3]>> {
    const WHAT: &str = "float32 or float64 points, shape (N, 3)";
    let a = array(points, "points", WHAT)?;
    shape(a, "points", &[None, Some(3)])?;
    if let Ok(p) = a.cast::<PyArray2<f32>>() {
        let p = p.readonly();
        let v = p.as_array();
        return Ok(v.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect());
    }
    if let Ok(p) = a.cast::<PyArray2<f64>>() {
        let p = p.readonly();
        let v = p.as_array();
        return Ok(v
            .rows()
            .into_iter()
            .map(|r| [r[0] as f32, r[1] as f32, r[2] as f32])
            .collect());
    }
    Err(PyTypeError::new_err(format!(
        "points must be {WHAT}, got dtype {}",
        dtype_name(a)
    )))
}
