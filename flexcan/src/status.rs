//! Controller state and error counters from `ESR1` and `ECR` (ACAN §17; Kinetis
//! reference manuals, FlexCAN "Error and Status 1 register", "Error Counter").
//!
//! - `ESR1.FLTCONF`: 00 error active, 01 error passive, 1x bus off;
//! - `ECR.TXERRCNT` / `ECR.RXERRCNT`: the counters; while bus-off the transmit count
//!   is reported as 256 (ACAN §17 convention, as twocan-core's
//!   [`ErrorCounters`] documents);
//! - `ESR1` bits 15–10 (BIT1ERR … STFERR) are the errors seen since `ESR1` was last
//!   read — reading clears them, so the driver reads `ESR1` in one place per call
//!   and keeps what it saw.

use twocan_core::{ErrorCounters, ErrorState, LastErrorCode};

use crate::regs::{ecr, esr1};

/// The fault-confinement state and counters of an `ESR1` / `ECR` pair.
pub const fn decode(esr1_value: u32, ecr_value: u32) -> (ErrorState, ErrorCounters) {
    let tec = ecr::TXERRCNT.get(ecr_value) as u16;
    let rec = ecr::RXERRCNT.get(ecr_value) as u16;
    match esr1::FLTCONF.get(esr1_value) {
        esr1::FLTCONF_ERROR_ACTIVE => {
            let c = ErrorCounters { tec, rec };
            // Active per FLTCONF; the warning level comes from the counters.
            let state = if tec >= 96 || rec >= 96 {
                ErrorState::Warning
            } else {
                ErrorState::Active
            };
            (state, c)
        }
        esr1::FLTCONF_ERROR_PASSIVE => (ErrorState::Passive, ErrorCounters { tec, rec }),
        _ => (ErrorState::BusOff, ErrorCounters { tec: 256, rec }),
    }
}

/// The error `ESR1` reports, if any. With several bits set, the one listed first
/// wins: bit errors, then acknowledge, CRC, form, stuff.
pub const fn last_error(esr1_value: u32) -> Option<LastErrorCode> {
    if esr1_value & esr1::BIT1ERR != 0 {
        // Sent recessive, read dominant.
        Some(LastErrorCode::BitRecessive)
    } else if esr1_value & esr1::BIT0ERR != 0 {
        // Sent dominant, read recessive.
        Some(LastErrorCode::BitDominant)
    } else if esr1_value & esr1::ACKERR != 0 {
        Some(LastErrorCode::Acknowledge)
    } else if esr1_value & esr1::CRCERR != 0 {
        Some(LastErrorCode::Crc)
    } else if esr1_value & esr1::FRMERR != 0 {
        Some(LastErrorCode::Form)
    } else if esr1_value & esr1::STFERR != 0 {
        Some(LastErrorCode::Stuff)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn states() {
        let fc = |v| esr1::FLTCONF.val(v);
        assert_eq!(
            decode(fc(0), 0x0102),
            (ErrorState::Active, ErrorCounters { tec: 2, rec: 1 })
        );
        assert_eq!(
            decode(fc(0), 96),
            (ErrorState::Warning, ErrorCounters { tec: 96, rec: 0 })
        );
        assert_eq!(decode(fc(1), 0x8000).0, ErrorState::Passive);
        assert_eq!(
            decode(fc(2), 0x0305),
            (ErrorState::BusOff, ErrorCounters { tec: 256, rec: 3 })
        );
        assert_eq!(decode(fc(3), 0).0, ErrorState::BusOff);
        assert_eq!(
            last_error(esr1::ACKERR | esr1::STFERR),
            Some(LastErrorCode::Acknowledge)
        );
        assert_eq!(last_error(esr1::BIT1ERR), Some(LastErrorCode::BitRecessive));
        assert_eq!(last_error(esr1::IDLE), None);
    }
}
