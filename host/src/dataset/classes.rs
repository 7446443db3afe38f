//! NYU40 class names and colours (PASCAL-VOC bit-interleave colormap).

/// NYU40 class names; index 0 is void.
pub const NYU40: [&str; 41] = [
    "void",
    "wall",
    "floor",
    "cabinet",
    "bed",
    "chair",
    "sofa",
    "table",
    "door",
    "window",
    "bookshelf",
    "picture",
    "counter",
    "blinds",
    "desk",
    "shelves",
    "curtain",
    "dresser",
    "pillow",
    "mirror",
    "floor mat",
    "clothes",
    "ceiling",
    "books",
    "refrigerator",
    "television",
    "paper",
    "towel",
    "shower curtain",
    "box",
    "whiteboard",
    "person",
    "night stand",
    "toilet",
    "sink",
    "lamp",
    "bathtub",
    "bag",
    "otherstructure",
    "otherfurniture",
    "otherprop",
];

/// Colour of label `i`: bits 0/1/2 of `i` go to bit 7 of R/G/B, the next three to bit 6,
/// and so on.
///
/// ```
/// use sndt_host::dataset::classes::color;
/// assert_eq!(color(0), [0, 0, 0]);
/// assert_eq!(color(1), [128, 0, 0]);
/// assert_eq!(color(2), [0, 128, 0]);
/// assert_eq!(color(7), [128, 128, 128]);
/// assert_eq!(color(8), [64, 0, 0]);
/// ```
pub fn color(label: u8) -> [u8; 3] {
    let mut c = [0u8; 3];
    let mut id = label;
    let mut shift = 7;
    while id > 0 {
        for (ch, v) in c.iter_mut().enumerate() {
            *v |= ((id >> ch) & 1) << shift;
        }
        id >>= 3;
        shift -= 1;
    }
    c
}

/// Colour for a rendered label: class colours, dark grey for invalid (255).
pub fn render_color(label: u8) -> [u8; 3] {
    if label == 255 {
        [40, 40, 40]
    } else {
        color(label)
    }
}
