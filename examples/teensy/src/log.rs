//! The examples' log of their key events (start-up, configuration, traffic counts, error
//! states, halts): `info!`, `warn!` and `error!` take `defmt`'s format syntax.
//!
//! With the crate's `defmt` feature, on the target, they are `defmt`'s macros: the frames
//! go to the RTT up-channel of `defmt-rtt` (the `_SEGGER_RTT` control block in RAM, which
//! a probe — or `can-fil` — reads), timestamped with the SysTick milliseconds. Otherwise
//! they log nothing; their arguments are still evaluated, by reference, so that a build
//! without the feature has no unused variable and the same behaviour.
//!
//! The STM32F7 examples include this very file (nothing in it is chip-specific).

// defmt's timestamp: milliseconds since start-up (the `ms` hint shows them as seconds).
#[cfg(all(target_os = "none", feature = "defmt"))]
defmt::timestamp!("{=u32:ms}", crate::time::millis());

/// Logs an event at the info level (`defmt::info!` with the `defmt` feature).
#[cfg(all(target_os = "none", feature = "defmt"))]
#[macro_export]
macro_rules! info {
    ($($t:tt)*) => { ::defmt::info!($($t)*) };
}

/// Logs a warning (`defmt::warn!` with the `defmt` feature).
#[cfg(all(target_os = "none", feature = "defmt"))]
#[macro_export]
macro_rules! warn {
    ($($t:tt)*) => { ::defmt::warn!($($t)*) };
}

/// Logs an error (`defmt::error!` with the `defmt` feature).
#[cfg(all(target_os = "none", feature = "defmt"))]
#[macro_export]
macro_rules! error {
    ($($t:tt)*) => { ::defmt::error!($($t)*) };
}

/// Logs an event at the info level (nothing without the `defmt` feature).
#[cfg(not(all(target_os = "none", feature = "defmt")))]
#[macro_export]
macro_rules! info {
    ($fmt:literal $(, $arg:expr)* $(,)?) => {{ $( let _ = &$arg; )* }};
}

/// Logs a warning (nothing without the `defmt` feature).
#[cfg(not(all(target_os = "none", feature = "defmt")))]
#[macro_export]
macro_rules! warn {
    ($fmt:literal $(, $arg:expr)* $(,)?) => {{ $( let _ = &$arg; )* }};
}

/// Logs an error (nothing without the `defmt` feature).
#[cfg(not(all(target_os = "none", feature = "defmt")))]
#[macro_export]
macro_rules! error {
    ($fmt:literal $(, $arg:expr)* $(,)?) => {{ $( let _ = &$arg; )* }};
}
