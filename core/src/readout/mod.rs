//! Reading the map back out along rays: [`Map::raycast`](crate::Map::raycast) one ray at a
//! time, and [`Map::render`](crate::Map::render), a label and distance image drawn Gaussian
//! by Gaussian over each one's pixel footprint.

pub(crate) mod raycast;
pub(crate) mod splat;

pub(crate) mod render;
