//! Legends for pictures: a white margin right of a picture with, per class shown, a colour
//! swatch and the class's NYU40 name, then a scale bar of a round number of metres and a
//! note. Text is drawn with `embedded-graphics`' built-in mono font through the
//! [`Canvas`]'s `DrawTarget`.

use crate::dataset::classes::{color, NYU40};
use embedded_graphics::mono_font::{ascii::FONT_8X13, MonoFont, MonoTextStyle};
use embedded_graphics::pixelcolor::{Rgb888, RgbColor};
use embedded_graphics::prelude::{DrawTarget, Drawable, OriginDimensions, Pixel, Point, Size};
use embedded_graphics::text::{Baseline, Text};

/// The font of every legend text: 8x13 pixels a character, about a swatch's height.
const FONT: &MonoFont<'static> = &FONT_8X13;
/// White space around the legend column, and between the picture and the column.
const PAD: u32 = 12;
/// Height of one legend row (swatch and name).
const ROW: u32 = 18;
/// Edge of a class's colour swatch.
const SWATCH: u32 = 14;
/// Space between a swatch and its name.
const GAP: u32 = 6;
/// The narrowest legend column: room for a scale bar even when all names are short.
const MIN_COLUMN: u32 = 120;
/// Colour of text, the scale bar and its ticks.
const INK: [u8; 3] = [0, 0, 0];

/// An RGB picture being drawn: 8 bits a channel, rows top to bottom, what
/// [`write_rgb`](crate::output::picture::write_rgb) takes. Pixels drawn outside it are
/// dropped.
///
/// ```
/// use sndt_host::output::legend::Canvas;
/// let c = Canvas::white(3, 2);
/// assert_eq!(c.as_rgb(), &[255u8; 18][..]);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Canvas {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

impl Canvas {
    /// A white canvas of `width` x `height` pixels.
    ///
    /// ```
    /// use sndt_host::output::legend::Canvas;
    /// let c = Canvas::white(4, 3);
    /// assert_eq!((c.width(), c.height(), c.pixel(3, 2)), (4, 3, [255, 255, 255]));
    /// ```
    pub fn white(width: u32, height: u32) -> Canvas {
        Canvas {
            width,
            height,
            rgb: vec![255; width as usize * height as usize * 3],
        }
    }

    /// Width in pixels.
    ///
    /// ```
    /// assert_eq!(sndt_host::output::legend::Canvas::white(5, 1).width(), 5);
    /// ```
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    ///
    /// ```
    /// assert_eq!(sndt_host::output::legend::Canvas::white(5, 1).height(), 1);
    /// ```
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The colour at column `x`, row `y` (panics outside the canvas).
    ///
    /// ```
    /// use sndt_host::output::legend::Canvas;
    /// let mut c = Canvas::white(2, 2);
    /// c.fill(1, 0, 1, 1, [9, 8, 7]);
    /// assert_eq!(c.pixel(1, 0), [9, 8, 7]);
    /// assert_eq!(c.pixel(0, 0), [255, 255, 255]);
    /// ```
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside"
        );
        let o = self.offset(x, y);
        [self.rgb[o], self.rgb[o + 1], self.rgb[o + 2]]
    }

    /// The pixels, 3 bytes each, row by row.
    ///
    /// ```
    /// use sndt_host::output::legend::Canvas;
    /// assert_eq!(Canvas::white(1, 1).as_rgb(), &[255, 255, 255]);
    /// ```
    pub fn as_rgb(&self) -> &[u8] {
        &self.rgb
    }

    /// Copies a `width` x `height` RGB picture (3 bytes a pixel, row by row) with its top
    /// left corner at (`x0`, `y0`); what falls outside the canvas is dropped.
    ///
    /// ```
    /// use sndt_host::output::legend::Canvas;
    /// let mut c = Canvas::white(3, 1);
    /// c.paste(1, 0, 1, 1, &[1, 2, 3]);
    /// assert_eq!(c.as_rgb(), &[255, 255, 255, 1, 2, 3, 255, 255, 255]);
    /// ```
    pub fn paste(&mut self, x0: u32, y0: u32, width: u32, height: u32, rgb: &[u8]) {
        assert_eq!(
            rgb.len(),
            width as usize * height as usize * 3,
            "picture size"
        );
        let w = width.min(self.width.saturating_sub(x0)) as usize;
        for y in 0..height.min(self.height.saturating_sub(y0)) {
            let src = (y * width) as usize * 3;
            let dst = self.offset(x0, y0 + y);
            self.rgb[dst..dst + 3 * w].copy_from_slice(&rgb[src..src + 3 * w]);
        }
    }

    /// Paints the `width` x `height` rectangle with top left corner (`x0`, `y0`) in
    /// `colour`, clipped to the canvas.
    ///
    /// ```
    /// use sndt_host::output::legend::Canvas;
    /// let mut c = Canvas::white(3, 3);
    /// c.fill(1, 1, 5, 5, [0, 0, 0]);
    /// assert_eq!((c.pixel(0, 0), c.pixel(1, 1), c.pixel(2, 2)), ([255; 3], [0; 3], [0; 3]));
    /// ```
    pub fn fill(&mut self, x0: u32, y0: u32, width: u32, height: u32, colour: [u8; 3]) {
        let x1 = x0.saturating_add(width).min(self.width);
        let y1 = y0.saturating_add(height).min(self.height);
        for y in y0..y1 {
            for x in x0..x1 {
                let o = self.offset(x, y);
                self.rgb[o..o + 3].copy_from_slice(&colour);
            }
        }
    }

    /// Writes `text` in black with the top left corner of its first character at (`x`,
    /// `y`), one [`text_width`]`(text)` wide and one line (13 pixels) high.
    ///
    /// ```
    /// use sndt_host::output::legend::Canvas;
    /// let mut c = Canvas::white(20, 13);
    /// c.text(0, 0, "l");
    /// assert!(c.as_rgb().iter().any(|&v| v == 0));
    /// ```
    pub fn text(&mut self, x: u32, y: u32, text: &str) {
        let ink = Rgb888::new(INK[0], INK[1], INK[2]);
        let at = Point::new(x as i32, y as i32);
        let drawn = Text::with_baseline(text, at, MonoTextStyle::new(FONT, ink), Baseline::Top);
        // Drawing on a canvas cannot fail (its error type has no value).
        let Ok(_) = drawn.draw(self);
    }

    /// Byte offset of pixel (`x`, `y`).
    fn offset(&self, x: u32, y: u32) -> usize {
        (y as usize * self.width as usize + x as usize) * 3
    }
}

impl OriginDimensions for Canvas {
    fn size(&self) -> Size {
        Size::new(self.width, self.height)
    }
}

impl DrawTarget for Canvas {
    type Color = Rgb888;
    type Error = core::convert::Infallible;

    fn draw_iter<I>(&mut self, pixels: I) -> Result<(), Self::Error>
    where
        I: IntoIterator<Item = Pixel<Rgb888>>,
    {
        for Pixel(p, c) in pixels {
            if let (Ok(x), Ok(y)) = (u32::try_from(p.x), u32::try_from(p.y))
                && x < self.width
                && y < self.height
            {
                let o = self.offset(x, y);
                self.rgb[o..o + 3].copy_from_slice(&[c.r(), c.g(), c.b()]);
            }
        }
        Ok(())
    }
}

/// Width in pixels of `text` written with [`Canvas::text`].
///
/// ```
/// use sndt_host::output::legend::text_width;
/// assert_eq!(text_width("wall"), 4 * 8);
/// assert_eq!(text_width(""), 0);
/// ```
pub fn text_width(text: &str) -> u32 {
    let advance = FONT.character_size.width + FONT.character_spacing;
    text.chars().count() as u32 * advance
}

/// The distinct labels among `labels`, in increasing order: the classes a legend lists.
///
/// ```
/// use sndt_host::output::legend::classes_present;
/// assert_eq!(classes_present([5, 1, 5, 0, 1]), vec![0, 1, 5]);
/// ```
pub fn classes_present(labels: impl IntoIterator<Item = u8>) -> Vec<u8> {
    let mut seen = [false; 256];
    for l in labels {
        seen[usize::from(l)] = true;
    }
    (0..=255u8).filter(|&c| seen[usize::from(c)]).collect()
}

/// Name of class `label`: its NYU40 name, or "class N" past the 40 classes.
///
/// ```
/// use sndt_host::output::legend::class_name;
/// assert_eq!(class_name(1), "wall");
/// assert_eq!(class_name(41), "class 41");
/// ```
pub fn class_name(label: u8) -> String {
    NYU40
        .get(usize::from(label))
        .map_or_else(|| format!("class {label}"), |n| (*n).to_string())
}

/// A scale bar: a round length in metres and its length in pixels.
///
/// ```
/// use sndt_host::output::legend::ScaleBar;
/// let bar = ScaleBar { metres: 2.0, pixels: 120 };
/// assert_eq!(bar.label(), "2 m");
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScaleBar {
    /// Length in metres: 1, 2 or 5 times a power of ten.
    pub metres: f32,
    /// Length in pixels, rounded to the nearest pixel.
    pub pixels: u32,
}

impl ScaleBar {
    /// The length as written beside the bar: metres from 1 m up, centimetres below.
    ///
    /// ```
    /// use sndt_host::output::legend::ScaleBar;
    /// assert_eq!(ScaleBar { metres: 5.0, pixels: 50 }.label(), "5 m");
    /// assert_eq!(ScaleBar { metres: 0.5, pixels: 50 }.label(), "50 cm");
    /// ```
    pub fn label(&self) -> String {
        if self.metres >= 1.0 {
            format!("{} m", self.metres)
        } else {
            format!("{} cm", (self.metres * 100.0).round())
        }
    }
}

/// The longest round length (1, 2 or 5 times a power of ten, 1 cm to 100 m) whose bar is at
/// most `max_pixels` long at `metres_per_pixel`; `None` when none fits or the scale is not
/// a positive number.
///
/// ```
/// use sndt_host::output::legend::{scale_bar, ScaleBar};
/// // 10 cm cells drawn 6 pixels wide: 60 pixels a metre.
/// assert_eq!(scale_bar(0.1 / 6.0, 150), Some(ScaleBar { metres: 2.0, pixels: 120 }));
/// assert_eq!(scale_bar(0.0, 150), None);
/// ```
pub fn scale_bar(metres_per_pixel: f32, max_pixels: u32) -> Option<ScaleBar> {
    const LENGTHS: [f32; 13] = [
        100.0, 50.0, 20.0, 10.0, 5.0, 2.0, 1.0, 0.5, 0.2, 0.1, 0.05, 0.02, 0.01,
    ];
    if !(metres_per_pixel.is_finite() && metres_per_pixel > 0.0) {
        return None;
    }
    LENGTHS
        .iter()
        .map(|&metres| ScaleBar {
            metres,
            pixels: (metres / metres_per_pixel).round() as u32,
        })
        .find(|b| (1..=max_pixels).contains(&b.pixels))
}

/// What a legend shows: the classes (swatch and name each, in this order), the picture's
/// scale, and a closing note (empty for none).
///
/// ```
/// use sndt_host::output::legend::Legend;
/// let l = Legend { classes: vec![1, 2], metres_per_pixel: 0.02, note: "darker: lower" };
/// assert_eq!(l.classes.len(), 2);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Legend<'a> {
    /// Labels, drawn in their [`color`] with their NYU40 name.
    pub classes: Vec<u8>,
    /// Metres on the ground per pixel of the picture.
    pub metres_per_pixel: f32,
    /// A line of text under the scale bar.
    pub note: &'a str,
}

/// `picture` (`width` x `height`, RGB) with `legend` in a white column on its right. The
/// picture's pixels are copied unchanged to the top left corner; the result is taller than
/// the picture only when the legend needs it.
///
/// ```
/// use sndt_host::output::legend::{with_legend, Legend};
/// let map = vec![7u8; 10 * 10 * 3];
/// let legend = Legend { classes: vec![1], metres_per_pixel: 0.01, note: "" };
/// let out = with_legend(&map, 10, 10, &legend);
/// assert!(out.width() > 10 && out.height() > 10);
/// assert_eq!(out.pixel(9, 9), [7, 7, 7]);
/// ```
pub fn with_legend(picture: &[u8], width: u32, height: u32, legend: &Legend) -> Canvas {
    let column = column_width(legend);
    let rows = legend.classes.len() as u32;
    let bar = scale_bar(legend.metres_per_pixel, column);
    // Class rows, then a blank half row, the bar's label and the bar (two rows), the note.
    let used = PAD + rows * ROW + ROW / 2 + 2 * ROW * u32::from(bar.is_some()) + ROW + PAD;
    let mut out = Canvas::white(width + PAD + column + PAD, height.max(used));
    out.paste(0, 0, width, height, picture);
    let x0 = width + PAD;
    let mut y = PAD;
    for &c in &legend.classes {
        draw_class_row(&mut out, x0, y, c);
        y += ROW;
    }
    y += ROW / 2;
    if let Some(bar) = bar {
        draw_scale_bar(&mut out, x0, y, bar);
        y += 2 * ROW;
    }
    out.text(x0, y, legend.note);
    out
}

/// Width of the legend column: the widest class row or note, at least [`MIN_COLUMN`].
fn column_width(legend: &Legend) -> u32 {
    let names = legend
        .classes
        .iter()
        .map(|&c| SWATCH + GAP + text_width(&class_name(c)));
    names
        .chain([text_width(legend.note), MIN_COLUMN])
        .max()
        .unwrap_or(MIN_COLUMN)
}

/// One legend row at (`x`, `y`): the swatch in the class's colour, then its name.
fn draw_class_row(out: &mut Canvas, x: u32, y: u32, class: u8) {
    out.fill(x, y + (ROW - SWATCH) / 2, SWATCH, SWATCH, color(class));
    let line = FONT.character_size.height;
    out.text(x + SWATCH + GAP, y + (ROW - line) / 2, &class_name(class));
}

/// The bar's label at (`x`, `y`) and, one row below, the bar: `bar.pixels` long from `x`,
/// 4 pixels thick, with a 2-pixel tick at each end so that its ends read clearly.
fn draw_scale_bar(out: &mut Canvas, x: u32, y: u32, bar: ScaleBar) {
    out.text(x, y, &bar.label());
    let top = y + ROW;
    out.fill(x, top + 3, bar.pixels, 4, INK);
    let tick = bar.pixels.min(2);
    out.fill(x, top, tick, 10, INK);
    out.fill(x + bar.pixels - tick, top, tick, 10, INK);
}

#[cfg(test)]
mod tests {
    use super::*;

    const WHITE: [u8; 3] = [255, 255, 255];

    /// Columns and rows of the non-white pixels of `c`: (min x, max x, min y, max y).
    fn ink_box(c: &Canvas) -> Option<(u32, u32, u32, u32)> {
        let mut b: Option<(u32, u32, u32, u32)> = None;
        for y in 0..c.height() {
            for x in 0..c.width() {
                if c.pixel(x, y) != WHITE {
                    b = Some(b.map_or((x, x, y, y), |(x0, x1, y0, y1)| {
                        (x0.min(x), x1.max(x), y0.min(y), y1.max(y))
                    }));
                }
            }
        }
        b
    }

    #[test]
    fn scale_bar_is_the_longest_round_length_that_fits() {
        // 10 cm cells at 6 pixels: 60 px/m. 5 m = 300 px and 2 m = 120 px; 1 m = 60 px.
        let mpp = 0.1 / 6.0;
        assert_eq!(
            scale_bar(mpp, 300).map(|b| (b.metres, b.pixels)),
            Some((5.0, 300))
        );
        assert_eq!(
            scale_bar(mpp, 299).map(|b| (b.metres, b.pixels)),
            Some((2.0, 120))
        );
        assert_eq!(
            scale_bar(mpp, 119).map(|b| (b.metres, b.pixels)),
            Some((1.0, 60))
        );
        // 1 cm cells at 16 pixels: 1600 px/m, so 10 cm = 160 px is the longest under 200.
        let bar = scale_bar(0.01 / 16.0, 200).unwrap();
        assert_eq!(
            (bar.metres, bar.pixels, bar.label()),
            (0.1, 160, "10 cm".into())
        );
        // 5 cm cells at 3 pixels: 1 m is 60 px (rounded from 59.999...).
        assert_eq!(scale_bar(0.05 / 3.0, 100).map(|b| b.pixels), Some(60));
    }

    #[test]
    fn scale_bar_refuses_what_cannot_be_drawn() {
        assert_eq!(scale_bar(f32::NAN, 100), None);
        assert_eq!(scale_bar(-0.01, 100), None);
        assert_eq!(scale_bar(f32::INFINITY, 100), None);
        // A pixel wider than 100 m leaves every length under one pixel.
        assert_eq!(scale_bar(1000.0, 100), None);
        // 1 cm is 10 pixels at 1 mm a pixel; a 5-pixel limit holds none.
        assert_eq!(scale_bar(0.001, 5), None);
    }

    #[test]
    fn legend_lists_exactly_the_classes_present() {
        let labels = [7u8, 1, 1, 33, 7, 2, 1];
        assert_eq!(classes_present(labels), vec![1, 2, 7, 33]);
        assert_eq!(classes_present([]), Vec::<u8>::new());
        assert_eq!(
            classes_present(labels)
                .iter()
                .map(|&c| class_name(c))
                .collect::<Vec<_>>(),
            ["wall", "floor", "table", "toilet"]
        );
    }

    #[test]
    fn swatches_have_their_class_colour_and_rows_follow_each_other() {
        let legend = Legend {
            classes: vec![1, 5, 40],
            metres_per_pixel: 0.02,
            note: "",
        };
        let out = with_legend(&[0; 20 * 30 * 3], 20, 30, &legend);
        // Row k's swatch starts PAD right of the picture, PAD + k rows + 2 down.
        let x = 20 + PAD + SWATCH / 2;
        for (k, (c, rgb)) in [(1, [128, 0, 0]), (5, [128, 0, 128]), (40, [64, 0, 64])]
            .into_iter()
            .enumerate()
        {
            let y = PAD + k as u32 * ROW + 2 + SWATCH / 2;
            assert_eq!(out.pixel(x, y), rgb, "class {c}");
            assert_eq!(color(c), rgb);
        }
    }

    #[test]
    fn the_picture_is_copied_unchanged_and_the_rest_is_legend() {
        let (w, h) = (40u32, 300u32);
        let picture: Vec<u8> = (0..w * h * 3).map(|i| (i % 251) as u8).collect();
        let legend = Legend {
            classes: vec![3],
            metres_per_pixel: 0.05,
            note: "n",
        };
        let out = with_legend(&picture, w, h, &legend);
        // Taller than the legend needs: the height is the picture's.
        assert_eq!((out.width(), out.height()), (w + PAD + MIN_COLUMN + PAD, h));
        for y in 0..h {
            let row = &out.as_rgb()[(y * out.width() * 3) as usize..][..(w * 3) as usize];
            assert_eq!(row, &picture[(y * w * 3) as usize..][..(w * 3) as usize]);
        }
        // The gap between the picture and the legend stays white.
        assert!((w..w + PAD).all(|x| (0..h).all(|y| out.pixel(x, y) == WHITE)));
    }

    #[test]
    fn text_is_drawn_inside_its_box_and_nowhere_else() {
        for s in ["wall", "otherfurniture", "1 m", "Ig"] {
            let mut c = Canvas::white(200, 40);
            c.text(10, 7, s);
            let (x0, x1, y0, y1) = ink_box(&c).expect(s);
            assert!(x0 >= 10 && x1 < 10 + text_width(s), "{s}: x {x0}..{x1}");
            assert!(y0 >= 7 && y1 < 7 + 13, "{s}: y {y0}..{y1}");
        }
        // Only ink and white: the font is drawn solid, without blending.
        let mut c = Canvas::white(40, 13);
        c.text(0, 0, "Ab");
        assert!(c.as_rgb().chunks(3).all(|p| p == WHITE || p == INK));
        // A capital I's stem is one column of ink several pixels tall.
        let mut c = Canvas::white(8, 13);
        c.text(0, 0, "I");
        let tallest = (0..8)
            .map(|x| (0..13).filter(|&y| c.pixel(x, y) == INK).count())
            .max();
        assert!(tallest >= Some(7), "{tallest:?}");
        // Nothing drawn for an empty text or far outside the canvas.
        let mut c = Canvas::white(8, 13);
        c.text(0, 0, "");
        c.text(100, 100, "x");
        assert_eq!(ink_box(&c), None);
    }

    #[test]
    fn the_scale_bar_is_as_long_as_computed() {
        let legend = Legend {
            classes: vec![],
            metres_per_pixel: 0.1 / 6.0,
            note: "",
        };
        let out = with_legend(&[], 0, 0, &legend);
        let bar = scale_bar(legend.metres_per_pixel, MIN_COLUMN).unwrap();
        // 60 pixels a metre: 2 m fill the narrowest column exactly.
        assert_eq!((bar.metres, bar.pixels), (2.0, MIN_COLUMN));
        // The bar's middle row, one row under its label: ink from PAD for 120 pixels.
        let y = PAD + ROW / 2 + ROW + 5;
        let ink: Vec<u32> = (0..out.width())
            .filter(|&x| out.pixel(x, y) == INK)
            .collect();
        assert_eq!(ink, (PAD..PAD + 120).collect::<Vec<_>>());
    }

    #[test]
    fn paste_and_fill_clip_at_the_edges() {
        let mut c = Canvas::white(2, 2);
        c.paste(1, 1, 2, 2, &[1; 12]);
        assert_eq!(c.pixel(1, 1), [1, 1, 1]);
        assert_eq!(c.pixel(0, 0), WHITE);
        c.fill(u32::MAX, u32::MAX, 5, 5, [0; 3]);
        assert_eq!(c.pixel(1, 0), WHITE);
    }
}
