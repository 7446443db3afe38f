//! Datasets: one frame type and one interface for every source.
//!
//! - [`frame`]: [`Frame`] (pose, rays, depth, labels, predictions) and [`FrameId`];
//! - [`source`]: the [`Dataset`] trait, [`Every`] (every k-th frame of another dataset)
//!   and the [`OpenOptions`] readers take;
//! - [`open`](open::open): detects a directory's layout, or renders `synthetic[:S:F]`
//!   (`synthetic:floor[:W[:F]]`);
//! - readers: [`synthetic`] (our scenes, rendered on the fly), [`prepared`] (the prepared
//!   layout, ours and the authors' v0.3.1), [`hypersim`] (raw Hypersim HDF5), [`npy`]
//!   (ESANet top-k predictions beside any of them), [`ros`] (ROS 2 bags);
//! - [`classes`]: the NYU40 class names and colours.
//!
//! Readers depend on [`frame`] and [`source`] only; [`open`](open::open) depends on the
//! readers.

pub mod classes;
pub mod frame;
pub mod hypersim;
pub mod npy;
pub mod open;
pub mod prepared;
pub mod ros;
pub mod source;
pub mod synthetic;

pub use frame::{Frame, FrameId, LabelSource, Rays, TopK};
pub use open::{open, open_spec};
pub use source::{Dataset, Every, OpenOptions};
