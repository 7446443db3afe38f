//! UART0 of the MPS2 board (`mps2-an386`): a CMSDK APB UART at `0x4000_4000`, used to
//! transmit only, by polling (no interrupt, no FIFO: the CMSDK UART buffers one byte).
//!
//! Registers (Cortex-M System Design Kit TRM, ARM DDI0479C, and QEMU's
//! `hw/char/cmsdk-apb-uart.c`): `DATA` +0x00 (a write sends a byte), `STATE` +0x04 (bit 0:
//! TX buffer full), `CTRL` +0x08 (bit 0: TX enable), `BAUDDIV` +0x10 (baud = PCLK /
//! BAUDDIV, at least 16). A byte written while TX is full is lost (an overrun), so
//! [`Uart::write`] waits for the buffer to drain before each byte. QEMU sends every byte at
//! once to the `-serial` backend (scripts/firmware.sh: `-serial file:...`), whatever the
//! baud rate; it only logs a guest error if TX is enabled with BAUDDIV below 16.
//!
//! This module is the firmware's only register access, and so holds its `unsafe`: two
//! volatile accesses to the UART's registers.

use core::sync::atomic::{AtomicBool, Ordering};

/// UART0's registers.
const BASE: usize = 0x4000_4000;
const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const BAUDDIV: usize = 0x10;
/// `STATE`: the TX buffer holds a byte not yet sent.
const TX_FULL: u32 = 1 << 0;
/// `CTRL`: transmitter on.
const TX_ENABLE: u32 = 1 << 0;

/// The peripheral clock of the MPS2 FPGA images (and QEMU's `mps2-an386`), Hz.
pub const PCLK_HZ: u32 = 25_000_000;
/// The divisor nearest 921,600 baud: 27, so 25 MHz / 27 = 925,926 baud (0.5 % fast,
/// well within a UART's tolerance). Each byte takes 10 bits on the line (8N1).
pub const BAUDDIV_921600: u32 = (PCLK_HZ + 921_600 / 2) / 921_600;

/// Set once UART0 has an owner.
static TAKEN: AtomicBool = AtomicBool::new(false);

/// The transmitter of UART0; one value exists at most.
pub struct Uart {
    _owned: (),
}

impl Uart {
    /// UART0, set to `PCLK_HZ / bauddiv` baud 8N1 with its transmitter on; `None` if it
    /// was taken already or `bauddiv` is below 16.
    pub fn take(bauddiv: u32) -> Option<Uart> {
        if bauddiv < 16 || TAKEN.swap(true, Ordering::AcqRel) {
            return None;
        }
        write_reg(BAUDDIV, bauddiv);
        write_reg(CTRL, TX_ENABLE);
        Some(Uart { _owned: () })
    }

    /// Sends `bytes`, waiting for room before each one.
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.flush();
            write_reg(DATA, b as u32);
        }
    }

    /// Waits until the last byte has left the TX buffer.
    pub fn flush(&mut self) {
        while read_reg(STATE) & TX_FULL != 0 {}
    }
}

fn read_reg(offset: usize) -> u32 {
    // SAFETY: BASE + offset is a 4-byte aligned register of UART0, which is always mapped
    // on this board; reading STATE has no side effect, and no Rust object lives there.
    unsafe { core::ptr::read_volatile((BASE + offset) as *const u32) }
}

fn write_reg(offset: usize, value: u32) {
    // SAFETY: as in `read_reg`; the writes are DATA (send a byte), CTRL and BAUDDIV, from
    // the single `Uart` owner (or its constructor), so no other code drives the UART.
    unsafe { core::ptr::write_volatile((BASE + offset) as *mut u32, value) }
}
