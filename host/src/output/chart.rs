//! Charts as SVG (plotters' SVG backend: text stays text, no font files needed).

use anyhow::{anyhow, Result};
use plotters::prelude::*;
use std::path::Path;

/// A grouped bar chart of per-class IoU (in %), one bar colour per series, over the
/// classes that have a value in any series.
///
/// ```
/// let dir = std::env::temp_dir().join(format!("sndt-chart-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let mut a = [None; 41];
/// a[1] = Some(0.9);
/// a[23] = Some(0.4);
/// let path = dir.join("iou.svg");
/// sndt_host::output::chart::iou_bars(&path, "IoU", &[("GT labels", &a)]).unwrap();
/// let svg = std::fs::read_to_string(&path).unwrap();
/// assert!(svg.contains("books") && svg.contains("wall"));
/// # std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn iou_bars(path: &Path, title: &str, series: &[(&str, &[Option<f64>; 41])]) -> Result<()> {
    crate::atomic::write_atomic(path, |tmp| iou_bars_to(tmp, title, series))
}

/// What [`iou_bars`] writes, into `path` directly.
fn iou_bars_to(path: &Path, title: &str, series: &[(&str, &[Option<f64>; 41])]) -> Result<()> {
    let classes: Vec<usize> = (1..=40)
        .filter(|&c| series.iter().any(|(_, s)| s[c].is_some()))
        .collect();
    let width = (120 + 28 * classes.len() * series.len().max(1)).max(640) as u32;
    let root = SVGBackend::new(path, (width, 480)).into_drawing_area();
    let err = |e: DrawingAreaErrorKind<_>| anyhow!("{}: {e:?}", path.display());
    root.fill(&WHITE).map_err(err)?;
    let n = classes.len().max(1) as f64;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(110)
        .y_label_area_size(50)
        .build_cartesian_2d(0f64..n, 0f64..100f64)
        .map_err(err)?;
    let names = classes.clone();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(classes.len() * 2 + 1)
        .x_label_formatter(&|x| {
            let i = x.floor() as usize;
            if (x - x.floor() - 0.5).abs() < 1e-6 && i < names.len() {
                crate::dataset::classes::NYU40[names[i]].to_string()
            } else {
                String::new()
            }
        })
        .x_label_style(
            ("sans-serif", 12)
                .into_font()
                .transform(FontTransform::Rotate90),
        )
        .y_desc("IoU (%)")
        .draw()
        .map_err(err)?;
    let palette = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
    ];
    let k = series.len().max(1) as f64;
    for (j, (name, values)) in series.iter().enumerate() {
        let colour = palette[j % palette.len()];
        let bars = classes.iter().enumerate().filter_map(|(i, &c)| {
            let v = values[c]? * 100.0;
            let x0 = i as f64 + 0.1 + 0.8 * j as f64 / k;
            Some(Rectangle::new(
                [(x0, 0.0), (x0 + 0.8 / k, v)],
                colour.filled(),
            ))
        });
        chart
            .draw_series(bars)
            .map_err(err)?
            .label(*name)
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], colour.filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// Named series of points `(x, y, label)`.
pub type LabelledSeries = [(String, Vec<(f64, f64, String)>)];

/// A scatter plot of map update rate (Hz, log scale) against mIoU (%): one marker colour
/// per series, each point labelled (e.g. with its cell size), points of a series joined.
///
/// ```
/// let dir = std::env::temp_dir().join(format!("sndt-rate-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let path = dir.join("rate.svg");
/// let s = vec![("S-NDT".to_string(), vec![(3.5, 72.0, "10cm".to_string()), (1.0, 78.0, "5cm".to_string())])];
/// sndt_host::output::chart::rate_vs_miou(&path, "rate", &s).unwrap();
/// let svg = std::fs::read_to_string(&path).unwrap();
/// assert!(svg.contains("S-NDT") && svg.contains("10cm"));
/// # std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn rate_vs_miou(path: &Path, title: &str, series: &LabelledSeries) -> Result<()> {
    crate::atomic::write_atomic(path, |tmp| rate_vs_miou_to(tmp, title, series))
}

/// What [`rate_vs_miou`] writes, into `path` directly.
fn rate_vs_miou_to(path: &Path, title: &str, series: &LabelledSeries) -> Result<()> {
    let all = series.iter().flat_map(|(_, p)| p.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0f64, f64::INFINITY, 0f64);
    for (x, y, _) in all {
        x0 = x0.min(*x);
        x1 = x1.max(*x);
        y0 = y0.min(*y);
        y1 = y1.max(*y);
    }
    if !(x0.is_finite() && x0 > 0.0) {
        (x0, x1, y0, y1) = (0.1, 10.0, 0.0, 100.0);
    }
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    let err = |e: DrawingAreaErrorKind<_>| anyhow!("{}: {e:?}", path.display());
    root.fill(&WHITE).map_err(err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(55)
        .build_cartesian_2d(
            ((x0 / 1.5)..(x1 * 1.5)).log_scale(),
            (y0 - 3.0).max(0.0)..(y1 + 3.0).min(100.0),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("map update rate (Hz, single thread)")
        .y_desc("mIoU (%)")
        .draw()
        .map_err(err)?;
    for (j, (name, points)) in series.iter().enumerate() {
        let colour = Palette99::pick(j).to_rgba();
        let mut sorted = points.clone();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(
                sorted.iter().map(|(x, y, _)| (*x, *y)),
                colour.stroke_width(1),
            ))
            .map_err(err)?
            .label(name.as_str())
            .legend(move |(x, y)| Circle::new((x + 5, y), 4, colour.filled()));
        chart
            .draw_series(sorted.iter().map(|(x, y, label)| {
                EmptyElement::at((*x, *y))
                    + Circle::new((0, 0), 4, colour.filled())
                    + Text::new(label.clone(), (6, -12), ("sans-serif", 11))
            }))
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// One panel of [`ghost_over_time`]: a title, the frame its object left (drawn as a
/// vertical line), and per map a name and its ghost share (0..=1) after each frame.
pub type GhostPanel<'a> = (String, u32, Vec<(String, &'a [f64])>);

/// Ghost surface over time: one panel per event, the share (%) of the object's former
/// surface each map still holds occupied after each frame, one line colour per map.
///
/// ```
/// let dir = std::env::temp_dir().join(format!("sndt-ghost-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let path = dir.join("ghost.svg");
/// let g = [1.0, 1.0, 0.5, 0.0];
/// let panel = ("chair moved".to_string(), 2, vec![("sndt 0.10".to_string(), &g[..])]);
/// sndt_host::output::chart::ghost_over_time(&path, "ghost", &[panel]).unwrap();
/// let svg = std::fs::read_to_string(&path).unwrap();
/// assert!(svg.contains("chair moved") && svg.contains("sndt 0.10"));
/// # std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn ghost_over_time(path: &Path, title: &str, panels: &[GhostPanel]) -> Result<()> {
    crate::atomic::write_atomic(path, |tmp| ghost_over_time_to(tmp, title, panels))
}

/// What [`ghost_over_time`] writes, into `path` directly.
fn ghost_over_time_to(path: &Path, title: &str, panels: &[GhostPanel]) -> Result<()> {
    let rows = panels.len().div_ceil(2).max(1);
    let root = SVGBackend::new(path, (1100, 60 + 300 * rows as u32)).into_drawing_area();
    let err = |e: DrawingAreaErrorKind<_>| anyhow!("{}: {e:?}", path.display());
    root.fill(&WHITE).map_err(err)?;
    let root = root.titled(title, ("sans-serif", 20)).map_err(err)?;
    for (area, (name, vacated, series)) in root.split_evenly((rows, 2)).iter().zip(panels) {
        let frames = series.iter().map(|(_, g)| g.len()).max().unwrap_or(1);
        let mut chart = ChartBuilder::on(area)
            .caption(name, ("sans-serif", 15))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(0f64..frames as f64, 0f64..105f64)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("frame")
            .y_desc("ghost (% of former surface)")
            .draw()
            .map_err(err)?;
        let at = *vacated as f64;
        chart
            .draw_series(LineSeries::new([(at, 0.0), (at, 105.0)], BLACK.mix(0.3)))
            .map_err(err)?;
        for (j, (label, ghost)) in series.iter().enumerate() {
            let colour = Palette99::pick(j).to_rgba();
            let line = ghost.iter().enumerate().map(|(t, g)| (t as f64, 100.0 * g));
            chart
                .draw_series(LineSeries::new(line, colour.stroke_width(2)))
                .map_err(err)?
                .label(label.as_str())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 15, y)], colour));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}
