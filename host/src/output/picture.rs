//! PNG pictures: label images side by side, a bird's-eye view of a semantic map.

use crate::dataset::classes::color;
use crate::output::legend::{classes_present, with_legend, Legend};
use anyhow::{Context, Result};
use sndt_core::{Map, Occupancy};
use std::path::Path;

/// Writes an 8-bit RGB PNG.
pub fn write_rgb(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<()> {
    crate::atomic::write_atomic(path, |tmp| write_rgb_to(tmp, width, height, rgb))
}

/// What [`write_rgb`] writes, into `path` directly.
fn write_rgb_to(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<()> {
    let file =
        std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc
        .write_header()
        .with_context(|| format!("writing {}", path.display()))?;
    w.write_image_data(rgb)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// Label images of equal size, coloured and placed side by side with a 4-pixel gap.
pub fn side_by_side(
    path: &Path,
    width: u32,
    height: u32,
    images: &[&[u8]],
    colour: impl Fn(u8) -> [u8; 3],
) -> Result<()> {
    let gap = 4u32;
    let total = width * images.len() as u32 + gap * (images.len() as u32).saturating_sub(1);
    let mut rgb = vec![255u8; (total * height * 3) as usize];
    for (k, img) in images.iter().enumerate() {
        let x0 = k as u32 * (width + gap);
        for y in 0..height {
            for x in 0..width {
                let c = colour(img[(y * width + x) as usize]);
                let o = ((y * total + x0 + x) * 3) as usize;
                rgb[o..o + 3].copy_from_slice(&c);
            }
        }
    }
    write_rgb(path, total, height, &rgb)
}

/// Top view of the map's occupied surface voxels below `z_max` metres: per column the
/// highest one, in its class colour, darker when lower; one square of pixels per voxel
/// column, north up. A white column on the right holds the legend: the classes drawn, a
/// scale bar and how to read the shading.
pub fn birds_eye<const V: usize, const B: usize, const C: usize>(
    path: &Path,
    map: &Map<V, B, C>,
    z_max: f32,
) -> Result<()> {
    let view = top_view(map, z_max)?;
    let legend = Legend {
        classes: view.classes,
        metres_per_pixel: view.metres_per_pixel,
        note: "darker: lower",
    };
    let out = with_legend(&view.rgb, view.width, view.height, &legend);
    write_rgb(path, out.width(), out.height(), out.as_rgb())
}

/// The map part of [`birds_eye`]'s picture, with what its legend needs.
struct TopView {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
    /// The classes of the columns drawn.
    classes: Vec<u8>,
    /// Metres on the ground per pixel: the cell size over the pixels per voxel.
    metres_per_pixel: f32,
}

/// Draws the map part of [`birds_eye`]'s picture.
fn top_view<const V: usize, const B: usize, const C: usize>(
    map: &Map<V, B, C>,
    z_max: f32,
) -> Result<TopView> {
    let h = map.config().cell_size;
    let cols: Vec<_> = map
        .voxels()
        .filter(|v| v.occupancy() == Occupancy::Occupied && v.gaussian.mean.z < z_max)
        .map(|v| {
            (
                v.key.x as i32,
                v.key.y as i32,
                v.gaussian.mean.z,
                v.class().map_or(0, |c| c.0),
            )
        })
        .collect();
    anyhow::ensure!(
        !cols.is_empty(),
        "map has no occupied voxels below {z_max} m"
    );
    let (x0, x1) = cols
        .iter()
        .fold((i32::MAX, i32::MIN), |a, c| (a.0.min(c.0), a.1.max(c.0)));
    let (y0, y1) = cols
        .iter()
        .fold((i32::MAX, i32::MIN), |a, c| (a.0.min(c.1), a.1.max(c.1)));
    let (z0, z1) = cols
        .iter()
        .fold((f32::MAX, f32::MIN), |a, c| (a.0.min(c.2), a.1.max(c.2)));
    // Pixels per voxel: at least 4 at 10 cm, and the longer side at least ~512 pixels.
    let span = (x1 - x0 + 1).max(y1 - y0 + 1) as f32;
    let s = ((4.0 * 0.1 / h).max(512.0 / span).clamp(2.0, 16.0)) as u32;
    let (w, hgt) = (((x1 - x0 + 1) as u32) * s, ((y1 - y0 + 1) as u32) * s);
    let mut top = vec![(f32::MIN, 0u8); ((x1 - x0 + 1) * (y1 - y0 + 1)) as usize];
    let cw = (x1 - x0 + 1) as usize;
    for &(x, y, z, c) in &cols {
        let i = (y1 - y) as usize * cw + (x - x0) as usize; // north up
        if z > top[i].0 {
            top[i] = (z, c);
        }
    }
    let mut rgb = vec![255u8; (w * hgt * 3) as usize];
    for (i, &(z, c)) in top.iter().enumerate() {
        if z == f32::MIN {
            continue;
        }
        let shade = 0.45 + 0.55 * ((z - z0) / (z1 - z0).max(1e-3));
        let col = color(c).map(|v| (v as f32 * shade + 20.0 * (1.0 - shade)) as u8);
        let (cx, cy) = ((i % cw) as u32 * s, (i / cw) as u32 * s);
        for py in cy..cy + s {
            for px in cx..cx + s {
                let o = ((py * w + px) * 3) as usize;
                rgb[o..o + 3].copy_from_slice(&col);
            }
        }
    }
    Ok(TopView {
        width: w,
        height: hgt,
        rgb,
        classes: classes_present(top.iter().filter(|t| t.0 != f32::MIN).map(|t| t.1)),
        metres_per_pixel: h / s as f32,
    })
}
