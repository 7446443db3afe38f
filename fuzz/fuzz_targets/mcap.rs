//! The ROS 2 bag reader (MCAP with CDR messages: depth and label images, camera info,
//! `/tf`) on arbitrary bytes, through `Bag::from_bytes`.
//!
//! An opened bag's frames must all load and pass `Frame::validate` (but for label ids
//! above 40, which the reader passes through by design), and then map (see
//! `sndt_fuzz::map_frame`).
#![no_main]

use libfuzzer_sys::fuzz_target;
use sndt_fuzz::map_frame;
use sndt_host::dataset::ros::bag::Bag;
use sndt_host::dataset::source::BagOptions;
use sndt_host::dataset::Dataset;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    // The command line's defaults (exact stamps, topics found by encoding).
    let options = BagOptions::default();
    let Ok(bag) = Bag::from_bytes(Path::new("fuzz.mcap"), data.to_vec(), &options) else {
        return;
    };
    let _ = (bag.describe(), bag.stamps());
    for id in bag.frames().iter().take(4) {
        let frame = bag.load(id).expect("a frame the bag lists loads");
        // Label ids above 40 pass through on purpose (a bag without a label map; mapping
        // counts them as rejected labels), so only they are exempt from the check.
        let mut checked = frame.clone();
        if let Some(labels) = checked.labels.as_mut() {
            labels.iter_mut().filter(|c| **c > 40).for_each(|c| *c = 0);
        }
        if let Err(e) = checked.validate() {
            panic!("bag frame {id} fails validation: {e:#}");
        }
        map_frame(&frame);
    }
});
