//! Bit timing (being written).
