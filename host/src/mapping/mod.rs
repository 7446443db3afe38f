//! Maps as the host runs them: what every mapper offers the evaluation, and the core's map
//! at host and device capacities.
//!
//! | file | job |
//! |---|---|
//! | [`semantic_map`] | the [`SemanticMap`] trait every mapper implements (integrate a frame, prepare a read-out, report memory), the core's side of it, and the tools' [`HostMap`] |
//! | [`global`] | [`GlobalMap`]: the host map that grows by tiers instead of evicting |
//! | [`stream`] | a device's record stream checked before anything of it is merged ([`check_stream`], [`merge_checked`]) |
//! | [`spilling`] | [`SpillingMap`]: a device-capacity map spilling every evicted record into a [`GlobalMap`], and what that costs on a link |
//! | [`device`] | the device capacities a run can simulate ([`DeviceCapacity`]) and [`with_device!`](crate::with_device), which names each one's map type |
//!
//! The files use each other downwards in this order (a spilling map merges into a global
//! map, which checks streams); the rest of the host imports from here.

pub mod device;
pub mod global;
pub mod semantic_map;
pub mod spilling;
pub mod stream;

pub use device::DeviceCapacity;
pub use global::{GlobalMap, Tier1, Tier2};
pub use semantic_map::{
    backproject, boxed_map, integrate_frame, integrate_frame_spilling, HostMap, LabelView,
    SemanticMap,
};
pub use spilling::{Spill, SpillStats, SpillingMap};
pub use stream::{check_stream, merge_checked, StreamError, StreamSummary};
