//! CRC-32 (IEEE 802.3, reflected, as in zlib/PNG) with a table built at compile time.

const TABLE: [u32; 256] = {
    let mut t = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
};

/// A running CRC-32 (IEEE 802.3, as zlib and PNG compute it): the checksum of snapshots
/// ([`Map::checksum`](crate::Map::checksum)). Public so that firmware can check other
/// buffers, such as a rendered view, the same way as the host does.
///
/// ```
/// let mut crc = sndt_core::Crc32::new();
/// crc.update(b"1234");
/// crc.update(b"56789");
/// assert_eq!(crc.finish(), 0xCBF4_3926); // the standard check value
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crc32(u32);

impl Default for Crc32 {
    fn default() -> Self {
        Self::new()
    }
}

impl Crc32 {
    /// The CRC of no bytes yet.
    ///
    /// ```
    /// assert_eq!(sndt_core::Crc32::new().finish(), 0);
    /// ```
    pub const fn new() -> Self {
        Crc32(0xFFFF_FFFF)
    }

    /// Adds `bytes`.
    ///
    /// ```
    /// let mut crc = sndt_core::Crc32::new();
    /// crc.update(b"a");
    /// assert_eq!(crc.finish(), 0xE8B7_BE43);
    /// ```
    pub fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = TABLE[((self.0 ^ b as u32) & 0xff) as usize] ^ (self.0 >> 8);
        }
    }

    /// The CRC-32 of every byte added so far.
    ///
    /// ```
    /// let mut crc = sndt_core::Crc32::new();
    /// crc.update(b"123456789");
    /// assert_eq!(crc.finish(), 0xCBF4_3926);
    /// ```
    pub fn finish(self) -> u32 {
        !self.0
    }
}

/// CRC-32 of a byte slice.
pub(crate) fn crc32(bytes: &[u8]) -> u32 {
    let mut c = Crc32::new();
    c.update(bytes);
    c.finish()
}

#[cfg(test)]
mod tests {
    #[test]
    fn check_value() {
        // The standard CRC-32 check value.
        assert_eq!(super::crc32(b"123456789"), 0xCBF4_3926);
    }
}
