//! Stack high-water marks by painting (`can-fil --stack`, read by `can-bench`).
//!
//! Before the first instruction, the RAM between the end of the statics (cortex-m-rt's
//! `_stack_end`) and the initial stack pointer (vector 0) is filled with [`PATTERN`].
//! The high-water mark is the distance from the initial stack pointer down to the
//! deepest word that no longer holds the pattern: everything the firmware's stack
//! (thread code, handlers and the exception frames the core pushed) ever wrote.
//!
//! Two marks are taken: at the first write to an NVIC `ISER` register that unmasks an
//! interrupt line of a CAN controller — the examples unmask their lines once the driver
//! is configured and split (`docs/architecture.md`), so this is the **configuration**
//! figure: reset, start-up and configuration — and at the end of the run (**whole
//! run**). Painting measures what is written: stack reserved and never written is not
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
    /// The high-water mark when the first CAN interrupt line was unmasked, and the core
    /// time then (ns).
    pub configuration: Option<(u32, u64)>,
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

/// Takes the configuration mark if the board paints its stack and has none yet (called
/// when an `ISER` write unmasks a CAN interrupt line).
pub fn mark_configuration(uc: &mut Unicorn<'_, Board>) {
    let Some(s) = uc.get_data().stack.clone() else {
        return;
    };
    if s.configuration.is_some() {
        return;
    }
    let mark = high_water(uc, &s);
    let now = uc.get_data().time_ns();
    if let Some(s) = uc.get_data_mut().stack.as_mut() {
        s.configuration = Some((mark, now));
    }
}
