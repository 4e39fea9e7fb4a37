//! Stack high-water marks by painting (`can-fil --stack`, read by `can-bench`).
//!
//! Before the first instruction, the RAM between the end of the statics (cortex-m-rt's
//! `_stack_end`) and the initial stack pointer (vector 0) is filled with [`PATTERN`].
//! The high-water mark is the distance from the initial stack pointer down to the
//! deepest word that no longer holds the pattern: everything the firmware's stack
//! (thread code, handlers and the exception frames the core pushed) ever wrote.
//!
//! Two marks are taken: when the last CAN controller the firmware starts has its first
//! interrupt line unmasked (an NVIC `ISER` write) — the examples unmask a controller's
//! lines once its driver is configured and split (`docs/architecture.md`), so this is
//! the **configuration** figure: reset, start-up and the configuration of every
//! controller, the second of two included (with whatever the first one's handlers
//! pushed meanwhile) — and at the end of the run (**whole run**). Painting measures what is written: stack reserved and never written is not
//! seen.

use unicorn_engine::Unicorn;

use crate::machine::Board;

/// The word the stack is painted with.
pub const PATTERN: u32 = 0xA5C3_5AE1;

/// A painted stack and the marks taken.
#[derive(Debug, Clone)]
pub struct StackPaint {
    /// Lowest painted address (`_stack_end`).
    pub bottom: u32,
    /// The initial stack pointer (one past the highest painted word).
    pub top: u32,
    /// The high-water mark when the last CAN controller started had its first
    /// interrupt line unmasked, and the core time then (ns).
    pub configuration: Option<(u32, u64)>,
    /// The controllers (index bits of the board's CAN ports) with a line unmasked so far.
    pub started: u32,
}

impl StackPaint {
    /// Bytes painted.
    pub fn painted(&self) -> u32 {
        self.top - self.bottom
    }
}

/// Paints `bottom..top` of the board's memory.
pub fn paint(uc: &mut Unicorn<'_, Board>, bottom: u32, top: u32) -> Result<StackPaint, String> {
    if bottom >= top || !bottom.is_multiple_of(4) || !top.is_multiple_of(4) {
        return Err(format!(
            "stack: no paintable stack between 0x{bottom:08X} and 0x{top:08X}"
        ));
    }
    let words = ((top - bottom) / 4) as usize;
    let bytes: Vec<u8> = std::iter::repeat_n(PATTERN.to_le_bytes(), words)
        .flatten()
        .collect();
    uc.mem_write(u64::from(bottom), &bytes)
        .map_err(|e| format!("stack: painting 0x{bottom:08X}..0x{top:08X}: {e:?}"))?;
    Ok(StackPaint {
        bottom,
        top,
        configuration: None,
        started: 0,
    })
}

/// The high-water mark now: bytes from the deepest word that lost the pattern up to
/// the initial stack pointer (0 if none did; the whole painted area if its lowest word
/// did, which may be an overflow).
pub fn high_water(uc: &Unicorn<'_, Board>, s: &StackPaint) -> u32 {
    let Ok(bytes) = uc.mem_read_as_vec(u64::from(s.bottom), s.painted() as usize) else {
        return s.painted();
    };
    let pattern = PATTERN.to_le_bytes();
    let untouched = bytes.chunks_exact(4).take_while(|w| *w == pattern).count() as u32;
    s.painted() - 4 * untouched
}

/// Takes the configuration mark again if the board paints its stack and `controllers`
/// (index bits) has one whose lines were not unmasked before (called when an `ISER`
/// write unmasks a CAN interrupt line): the mark of the last controller started stays.
pub fn mark_configuration(uc: &mut Unicorn<'_, Board>, controllers: u32) {
    let Some(s) = uc.get_data().stack.clone() else {
        return;
    };
    if !starts_another(s.started, controllers) {
        return;
    }
    let mark = high_water(uc, &s);
    let now = uc.get_data().time_ns();
    if let Some(s) = uc.get_data_mut().stack.as_mut() {
        s.configuration = Some((mark, now));
        s.started |= controllers;
    }
}

/// Whether an `ISER` write unmasking lines of `controllers` (index bits) starts a
/// controller none of whose lines was unmasked before (`started`).
fn starts_another(started: u32, controllers: u32) -> bool {
    controllers & !started != 0
}

#[cfg(test)]
mod tests {
    use super::starts_another;

    /// The configuration mark follows each controller's first line, not its other
    /// lines: a two-controller firmware's mark includes the second configuration.
    #[test]
    fn the_mark_moves_with_each_controller_started() {
        assert!(starts_another(0, 0b01), "the first controller's first line");
        assert!(!starts_another(0b01, 0b01), "its other lines");
        assert!(
            starts_another(0b01, 0b10),
            "the second controller's first line"
        );
        assert!(
            !starts_another(0b11, 0b10),
            "the second controller's other lines"
        );
        assert!(!starts_another(0b01, 0), "no CAN line");
    }
}
