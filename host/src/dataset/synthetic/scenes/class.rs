//! NYU40 ids used here beyond those in [`crate::dataset::synthetic::room::nyu`].
#![allow(missing_docs)]

pub use crate::dataset::synthetic::room::nyu::*;
pub const CABINET: u8 = 3;
pub const CHAIR: u8 = 5;
pub const SOFA: u8 = 6;
pub const DOOR: u8 = 8;
pub const WINDOW: u8 = 9;
pub const BOOKSHELF: u8 = 10;
pub const COUNTER: u8 = 12;
pub const BLINDS: u8 = 13;
pub const DESK: u8 = 14;
pub const CURTAIN: u8 = 16;
pub const DRESSER: u8 = 17;
pub const PILLOW: u8 = 18;
pub const MIRROR: u8 = 19;
pub const FLOOR_MAT: u8 = 20;
pub const CLOTHES: u8 = 21;
pub const REFRIGERATOR: u8 = 24;
pub const TELEVISION: u8 = 25;
pub const PAPER: u8 = 26;
pub const TOWEL: u8 = 27;
pub const SHOWER_CURTAIN: u8 = 28;
pub const BOX: u8 = 29;
pub const WHITEBOARD: u8 = 30;
pub const PERSON: u8 = 31;
pub const NIGHT_STAND: u8 = 32;
pub const TOILET: u8 = 33;
pub const SINK: u8 = 34;
pub const BATHTUB: u8 = 36;
pub const BAG: u8 = 37;
pub const OTHER_STRUCTURE: u8 = 38;
pub const OTHER_FURNITURE: u8 = 39;
pub const OTHER_PROP: u8 = 40;
/// Unlabelled geometry.
pub const VOID: u8 = 0;
