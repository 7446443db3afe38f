//! The view every target renders from the test vector's map: a 64 x 48 image from the last
//! frame's pose, with the vector camera's field of view. Its CRC is the render's
//! counterpart of the snapshot CRC: the Cortex-M4F firmware, x86-64 and aarch64 must all
//! arrive at `targets/cortex-m4f/vector/expected_render_crc.txt`.
//!
//! The CRC is CRC-32 (IEEE, [`Crc32`]) over the pixels in row-major order, each as its
//! label byte ([`INVALID_LABEL`] for no hit) then its distance along the ray as
//! little-endian `f32` bytes (0 for no hit).

use sndt_core::{Crc32, Isometry3, Map, Pinhole, INVALID_LABEL};

/// Width of the view, pixels.
pub const VIEW_WIDTH: u32 = 64;
/// Height of the view, pixels.
pub const VIEW_HEIGHT: u32 = 48;

/// The view's camera: `camera` scaled to 64 x 48 with the principal point at the centre.
/// The firmware computes it with the same `f32` operations, so the bits agree.
///
/// ```
/// use sndt_host::embedded::view::view_camera;
/// use sndt_core::Pinhole;
/// let c = view_camera(&Pinhole { fx: 120.0, fy: 120.0, cx: 80.0, cy: 60.0, width: 160, height: 120 });
/// assert_eq!((c.fx, c.fy, c.cx, c.cy, c.width, c.height), (48.0, 48.0, 32.0, 24.0, 64, 48));
/// ```
pub fn view_camera(camera: &Pinhole) -> Pinhole {
    Pinhole {
        fx: camera.fx * VIEW_WIDTH as f32 / camera.width as f32,
        fy: camera.fy * VIEW_HEIGHT as f32 / camera.height as f32,
        cx: VIEW_WIDTH as f32 / 2.0,
        cy: VIEW_HEIGHT as f32 / 2.0,
        width: VIEW_WIDTH,
        height: VIEW_HEIGHT,
    }
}

/// A rendered view and its checks.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewRender {
    /// The view's camera.
    pub camera: Pinhole,
    /// Label per pixel, row-major ([`INVALID_LABEL`] = no hit).
    pub labels: Vec<u8>,
    /// Distance along the ray per pixel, metres (0 = no hit).
    pub distance: Vec<f32>,
    /// CRC-32 of the pixels (module doc).
    pub crc: u32,
}

impl ViewRender {
    /// Renders `map` from `pose` with [`view_camera`]`(camera)`.
    ///
    /// ```
    /// use sndt_host::embedded::view::ViewRender;
    /// use sndt_core::*;
    /// let map: Map<64, 16, 40> = Map::new(Config::DEFAULT);
    /// let cam = Pinhole { fx: 120.0, fy: 120.0, cx: 80.0, cy: 60.0, width: 160, height: 120 };
    /// let v = ViewRender::new(&map, &cam, &Isometry3::identity()).unwrap();
    /// assert_eq!(v.hits(), 0); // an empty map shows nothing
    /// ```
    pub fn new<const V: usize, const B: usize, const C: usize>(
        map: &Map<V, B, C>,
        camera: &Pinhole,
        pose: &Isometry3<f32>,
    ) -> anyhow::Result<ViewRender> {
        let camera = view_camera(camera);
        let n = (VIEW_WIDTH * VIEW_HEIGHT) as usize;
        let (mut labels, mut distance) = (vec![0u8; n], vec![0f32; n]);
        map.render(pose, &camera, &mut labels, &mut distance)
            .map_err(|e| anyhow::anyhow!("rendering the {VIEW_WIDTH}x{VIEW_HEIGHT} view: {e:?}"))?;
        let mut crc = Crc32::new();
        for (&l, d) in labels.iter().zip(&distance) {
            crc.update(&[l]);
            crc.update(&d.to_le_bytes());
        }
        Ok(ViewRender {
            camera,
            labels,
            distance,
            crc: crc.finish(),
        })
    }

    /// Pixels that hit the map.
    pub fn hits(&self) -> usize {
        self.labels.iter().filter(|&&l| l != INVALID_LABEL).count()
    }

    /// `(label, pixels)` for every label shown, by label ([`INVALID_LABEL`] last).
    pub fn histogram(&self) -> Vec<(u8, usize)> {
        let mut counts = [0usize; 256];
        for &l in &self.labels {
            counts[l as usize] += 1;
        }
        (0..=255u8).zip(counts).filter(|&(_, n)| n > 0).collect()
    }
}
