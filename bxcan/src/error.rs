//! `Display` and [`core::error::Error`] for the error types of this crate
//! ([`ConfigError`], [`BankError`], [`PlanError`]): one place, so that the modules that
//! define them keep to their own job.

use core::fmt;

use crate::config::ConfigError;
use crate::filters::{BankError, PlanError};

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConfigError::Timing(_) => f.write_str("no usable bit timing"),
            ConfigError::BtrReservedBits => {
                f.write_str("CAN_BTR value with bits outside BRP, TS1, TS2 and SJW")
            }
            ConfigError::StartBankOutOfRange => {
                f.write_str("CAN2 start bank above 28, or on a part without CAN2")
            }
            ConfigError::ClockAboveChipLimit => f.write_str("APB1 clock above the part's limit"),
        }
    }
}

impl core::error::Error for ConfigError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            ConfigError::Timing(e) => Some(e),
            _ => None,
        }
    }
}

impl fmt::Display for BankError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BankError::Filter { slot, .. } => write!(f, "filter of slot {slot} does not conform"),
            BankError::NotRepresentable { slot } => {
                write!(f, "slot {slot} cannot represent the filter exactly")
            }
        }
    }
}

impl core::error::Error for BankError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            BankError::Filter { error, .. } => Some(error),
            BankError::NotRepresentable { .. } => None,
        }
    }
}

impl fmt::Display for PlanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PlanError::Filter { index, .. } => write!(f, "filter {index} does not conform"),
            PlanError::TooManyFilters { given, max } => {
                write!(f, "{given} filters given, the planner takes at most {max}")
            }
            PlanError::DualTooManyBanks {
                can1_needed,
                can2_needed,
                available,
            } => write!(
                f,
                "CAN1 needs {can1_needed} and CAN2 {can2_needed} filter banks, {available} are shared"
            ),
            PlanError::TooManyBanks { needed, available } => write!(
                f,
                "the filters need {needed} filter banks, {available} are available"
            ),
            PlanError::TooManyLookupKeys { needed, max } => write!(
                f,
                "the merged filters leave {needed} identifiers to the driver's lookup, which holds {max}"
            ),
            PlanError::TooManyMatchIndices { needed, max } => write!(
                f,
                "the filters number {needed} match indices in a FIFO, the driver's map holds {max}"
            ),
            PlanError::BankOutOfRange => f.write_str("filter bank index above 27"),
        }
    }
}

impl core::error::Error for PlanError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            PlanError::Filter { error, .. } => Some(error),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::ToString;

    use super::*;
    use core::error::Error as _;
    use twocan_core::FilterError;

    #[test]
    fn messages_and_sources() {
        let e = PlanError::TooManyBanks {
            needed: 30,
            available: 14,
        };
        assert_eq!(
            e.to_string(),
            "the filters need 30 filter banks, 14 are available"
        );
        assert!(e.source().is_none());
        let e = PlanError::Filter {
            index: 3,
            error: FilterError::IdOutOfRange,
        };
        assert_eq!(e.to_string(), "filter 3 does not conform");
        assert_eq!(
            e.source().map(|s| s.to_string()).as_deref(),
            Some("filter identifier wider than its format")
        );
        let e = BankError::NotRepresentable { slot: 2 };
        assert_eq!(e.to_string(), "slot 2 cannot represent the filter exactly");
        let e = ConfigError::Timing(twocan_core::timing::TimingError::ClockZero);
        assert!(e.source().is_some());
    }
}
