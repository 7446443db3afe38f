//! The device capacities a host run can simulate (`--device V,B`): each is its own
//! compiled [`SpillingMap`](super::SpillingMap) type, and [`with_device!`](crate::with_device)
//! picks the one a [`DeviceCapacity`] names.

/// The device capacities `--device V,B` offers (each is its own compiled map type).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceCapacity {
    /// 1,024 voxels, 128 blocks (~120 KiB).
    Small,
    /// 4,096 voxels, 512 blocks: the Cortex-M4F example's map (~480 KiB).
    Firmware,
    /// 16,384 voxels, 2,048 blocks (~1.9 MiB).
    Large,
}

impl DeviceCapacity {
    /// Every capacity, as (capacity, voxels, blocks).
    pub const ALL: [(DeviceCapacity, usize, usize); 3] = [
        (DeviceCapacity::Small, 1024, 128),
        (DeviceCapacity::Firmware, 4096, 512),
        (DeviceCapacity::Large, 16384, 2048),
    ];

    /// `V,B`, one of [`DeviceCapacity::ALL`].
    ///
    /// ```
    /// use sndt_host::mapping::DeviceCapacity;
    /// assert_eq!(DeviceCapacity::parse("4096,512").unwrap(), DeviceCapacity::Firmware);
    /// assert!(DeviceCapacity::parse("4000,512").is_err());
    /// ```
    pub fn parse(s: &str) -> Result<DeviceCapacity, String> {
        let parsed = s.split_once(',').and_then(|(v, b)| {
            Some((
                v.trim().parse::<usize>().ok()?,
                b.trim().parse::<usize>().ok()?,
            ))
        });
        let offered = || {
            DeviceCapacity::ALL
                .iter()
                .map(|(_, v, b)| format!("{v},{b}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        match parsed {
            Some((v, b)) => DeviceCapacity::ALL
                .iter()
                .find(|&&(_, cv, cb)| (cv, cb) == (v, b))
                .map(|&(c, _, _)| c)
                .ok_or_else(|| {
                    format!(
                        "no device map of {v} voxels and {b} blocks; offered: {}",
                        offered()
                    )
                }),
            None => Err(format!("expected VOXELS,BLOCKS (one of {})", offered())),
        }
    }

    /// (voxels, blocks).
    pub fn capacity(self) -> (usize, usize) {
        DeviceCapacity::ALL
            .iter()
            .find(|(c, _, _)| *c == self)
            .map_or((0, 0), |&(_, v, b)| (v, b))
    }
}

/// `$body` with `$M` the [`SpillingMap`](crate::mapping::SpillingMap) type of capacity `$cap`.
#[macro_export]
macro_rules! with_device {
    ($cap:expr, $M:ident => $body:expr) => {
        match $cap {
            $crate::mapping::device::DeviceCapacity::Small => {
                type $M = $crate::mapping::spilling::SpillingMap<1024, 128>;
                $body
            }
            $crate::mapping::device::DeviceCapacity::Firmware => {
                type $M = $crate::mapping::spilling::SpillingMap<4096, 512>;
                $body
            }
            $crate::mapping::device::DeviceCapacity::Large => {
                type $M = $crate::mapping::spilling::SpillingMap<16384, 2048>;
                $body
            }
        }
    };
}
