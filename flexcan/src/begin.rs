//! `begin`: check everything, then configure the module (ACAN §15).
//!
//! [`check`] computes every error flag of ACAN table 5 at once without any
//! hardware access. [`FlexCan::begin`] runs the same check and returns
//! [`BeginError::Config`] before writing any register; only valid settings reach the
//! hardware, in the order of the Kinetis reference manuals' "FlexCAN initialization
//! sequence":
//!
//! The bit timing is judged by the driver's one rule ([`Settings::timing_rule`],
//! [`TimingRule::accept`]), the rule the running controller applies to `set_timing` and
//! `set_bitrate` and reports in its capabilities: a wished rate outside its range is
//! [`BeginError::Timing`] (`check`: [`ConfigErrors::BIT_RATE_OUT_OF_RANGE`]), a timing
//! it refuses [`ConfigErrors::BIT_TIMING_INCONSISTENT`] or
//! [`ConfigErrors::BIT_TIMING_FORBIDDEN`], a timing too far from the wished rate
//! [`ConfigErrors::BIT_RATE_TOO_FAR`].
//!
//!
//! 1. SIM clock gates of the ports and the module, pin mux of Tx and Rx (ALT2, open
//!    drain, pull-up; ACAN §7, §16.7.5–6);
//! 2. module disabled (`MDIS`, wait `LPMACK`), engine clock = oscillator
//!    (`CTRL1.CLKSRC` = 0, writable only while disabled), module enabled;
//! 3. soft reset (`SOFTRST`, wait until it clears), freeze (wait `FRZACK`);
//! 4. in freeze: `MCR` (Rx FIFO, individual masks, abort enable, self reception,
//!    format A, 16 MBs, warnings), `CTRL1` (bit timing, listen-only, loop-back,
//!    automatic bus-off recovery, error interrupt masks), `CTRL2` (`RFFN`, remote frames stored), the ID filter
//!    table, `RXIMR`, `RXFGMASK`, the transmit mailboxes inactive, flags cleared,
//!    `IMASK1` (FIFO frames available and overflow, every transmit mailbox);
//! 5. leave freeze (wait `FRZACK` and `NOTRDY` to clear), then wait until the module
//!    is synchronised to the bus (`ESR1.SYNCH`, 11 recessive bits; internal in
//!    loop-back mode): when `begin` returns, a frame starting on the bus is received.
//!
//! Every wait is bounded by [`Settings::handshake_bound`]; a missing acknowledge is
//! [`BeginError::Hardware`]`(`[`Error::Timeout`]`)`.

use twocan_core::timing::{TimingError, TimingRule};
use twocan_core::{BusMode, BusOffRecovery, Error, Filter, Registers};

use crate::begin_error::{BeginError, ConfigErrors};
use crate::can_clock::CanClock;
use crate::configuration::{Configuration, DATA_MAILBOX, MESSAGE_BUFFERS};
use crate::controller::FlexCan;
use crate::filters::FilterTable;
use crate::handshake;
use crate::imxrt::ImxrtPlan;
use crate::instance::Target;
use crate::regs::{
    self, code, cs, ctrl1, ctrl2, iflag1, mcr, CTRL1, CTRL2, IFLAG1, IFLAG2, IMASK1, IMASK2, MCR,
};
use crate::settings::Settings;
use crate::system::{choose_pins, PortPlan, SystemPlan};

/// Everything `begin` will write, computed before anything is written.
#[derive(Debug, Clone)]
struct Plan {
    system: SystemPlan,
    mcr: u32,
    ctrl1: u32,
    configuration: Configuration,
    table: FilterTable,
    /// The module's message buffers (16 or 64, [`crate::Chip::message_buffers`]).
    message_buffers: usize,
}

/// The checks of ACAN table 5, all of them, then the register values.
fn plan(
    target: Target,
    settings: &Settings,
    primary: &[Filter],
    secondary: &[Filter],
) -> Result<Plan, ConfigErrors> {
    let mut errors = timing_errors(&settings.timing_rule(), settings);
    let timing_bits = settings.timing.flexcan_ctrl1();
    if timing_bits.is_err() {
        errors |= ConfigErrors::BIT_TIMING_INCONSISTENT;
    }

    let table = FilterTable::compile(settings.configuration, primary, secondary);
    if let Err(e) = &table {
        errors |= *e;
    }

    let chip = target.board.chip();
    if !settings.can_clock.fits(chip) {
        errors |= ConfigErrors::CLOCK_NOT_ON_CHIP;
    }
    let system = match (chip.is_imxrt(), target.clock_gate()) {
        (_, None) => {
            errors |= ConfigErrors::NO_SUCH_INSTANCE;
            None
        }
        (true, Some(gate)) => imxrt_system(target, gate, settings, &mut errors),
        (false, Some(gate)) => kinetis_system(target, gate, settings, &mut errors),
    };

    match (errors.is_empty(), timing_bits, table, system) {
        (true, Ok(timing_bits), Ok(table), Some(system)) => {
            let mut mcr = mcr::FRZ
                | mcr::HALT
                | mcr::RFEN
                | mcr::IRMQ
                | mcr::AEN
                | mcr::IDAM.val(mcr::IDAM_FORMAT_A)
                | mcr::MAXMB.val(MESSAGE_BUFFERS as u32 - 1);
            if !settings.self_reception {
                mcr |= mcr::SRXDIS;
            }
            let mut ctrl1 = timing_bits;
            if settings.listen_only {
                ctrl1 |= ctrl1::LOM;
            }
            if settings.loop_back {
                ctrl1 |= ctrl1::LPB;
            }
            if settings.bus_off_recovery == BusOffRecovery::Manual {
                ctrl1 |= ctrl1::BOFFREC;
            }
            if settings.error_interrupts {
                ctrl1 |= ctrl1::ERRMSK | ctrl1::BOFFMSK | ctrl1::TWRNMSK | ctrl1::RWRNMSK;
                mcr |= mcr::WRNEN;
            }
            Ok(Plan {
                system,
                mcr,
                ctrl1,
                configuration: settings.configuration,
                table,
                message_buffers: chip.message_buffers(),
            })
        }
        _ => Err(errors),
    }
}

/// The Kinetis SIM/PORT plan: the pins of ACAN §7 (alternates on request).
fn kinetis_system(
    target: Target,
    gate: (usize, u32),
    settings: &Settings,
    errors: &mut ConfigErrors,
) -> Option<SystemPlan> {
    let pins = target.board.pins(target.instance)?;
    match choose_pins(
        pins,
        settings.use_alternate_tx_pin,
        settings.use_alternate_rx_pin,
    ) {
        Ok((tx, rx)) => Some(SystemPlan::Kinetis(PortPlan::new(
            gate,
            tx,
            rx,
            settings.tx_pin_open_collector,
            settings.rx_pin_pull_up,
        ))),
        Err((no_tx, no_rx)) => {
            if no_tx {
                *errors |= ConfigErrors::NO_ALTERNATE_TX_PIN;
            }
            if no_rx {
                *errors |= ConfigErrors::NO_ALTERNATE_RX_PIN;
            }
            None
        }
    }
}

/// The RT1062 CCM/IOMUXC plan: the board's one pin pair (no alternates on the Teensy
/// 4.x, so asking for one is [`ConfigErrors::NO_ALTERNATE_TX_PIN`] /
/// [`ConfigErrors::NO_ALTERNATE_RX_PIN`]), the clock root of the settings.
fn imxrt_system(
    target: Target,
    gate: (usize, u32),
    settings: &Settings,
    errors: &mut ConfigErrors,
) -> Option<SystemPlan> {
    let pins = target.board.imx_pins(target.instance)?;
    if settings.use_alternate_tx_pin {
        *errors |= ConfigErrors::NO_ALTERNATE_TX_PIN;
    }
    if settings.use_alternate_rx_pin {
        *errors |= ConfigErrors::NO_ALTERNATE_RX_PIN;
    }
    match settings.can_clock {
        CanClock::Imxrt(root) if errors.is_empty() => Some(SystemPlan::Imxrt(ImxrtPlan::new(
            gate,
            root,
            pins.tx,
            pins.rx,
            settings.tx_pin_open_collector,
            settings.rx_pin_pull_up,
        ))),
        _ => None,
    }
}

/// The table-5 flags of the bit timing, by the driver's rule ([`TimingRule::accept`]'s
/// three questions, each asked on its own so that every flag that applies is set): the
/// wished rate out of the rule's range ([`ConfigErrors::BIT_RATE_OUT_OF_RANGE`]; no
/// timing at all accepted, a bus clock below the CAN clock:
/// [`ConfigErrors::BIT_TIMING_FORBIDDEN`]); the timing refused
/// ([`ConfigErrors::BIT_TIMING_INCONSISTENT`] for another clock, layout or inconsistent
/// counts, ACAN §15.2.2; [`ConfigErrors::BIT_TIMING_FORBIDDEN`] for the Kinetis
/// manual's rules); the timing too far from the wished rate
/// ([`ConfigErrors::BIT_RATE_TOO_FAR`], ACAN §15.2.1).
fn timing_errors(rule: &TimingRule, settings: &Settings) -> ConfigErrors {
    let mut errors = ConfigErrors::NONE;
    match rule.check_bitrate(settings.wished_bit_rate()) {
        Ok(()) => {}
        Err(TimingError::ForbiddenByManual) => errors |= ConfigErrors::BIT_TIMING_FORBIDDEN,
        Err(_) => errors |= ConfigErrors::BIT_RATE_OUT_OF_RANGE,
    }
    if !settings.bit_rate_close_to_wished() {
        errors |= ConfigErrors::BIT_RATE_TOO_FAR;
    }
    match rule.check_timing(&settings.timing) {
        Ok(()) => {}
        Err(TimingError::ForbiddenByManual) => errors |= ConfigErrors::BIT_TIMING_FORBIDDEN,
        Err(_) => errors |= ConfigErrors::BIT_TIMING_INCONSISTENT,
    }
    errors
}

/// The error `begin` gives before any other check: the wished rate outside the range of
/// the driver's rule ([`TimingRule::check_bitrate`]; a rule that accepts nothing is left
/// to the flags, [`ConfigErrors::BIT_TIMING_FORBIDDEN`]).
fn bitrate_error(settings: &Settings) -> Option<TimingError> {
    match settings
        .timing_rule()
        .check_bitrate(settings.wished_bit_rate())
    {
        Ok(()) | Err(TimingError::ForbiddenByManual) => None,
        Err(e) => Some(e),
    }
}

/// Writes the plan (steps 2–5 of the module docs).
fn configure<R: Registers>(regs: &mut R, plan: &Plan, polls: u32) -> Result<(), Error> {
    handshake::disable(regs, polls)?;
    regs.modify32(CTRL1, |v| v & !ctrl1::CLKSRC);
    handshake::enable(regs, polls)?;
    handshake::soft_reset(regs, polls)?;
    handshake::freeze(regs, polls)?;

    let supervisor = regs.read32(MCR) & mcr::SUPV;
    regs.write32(MCR, plan.mcr | supervisor);
    regs.write32(CTRL1, plan.ctrl1);
    regs.modify32(CTRL2, |v| {
        let kept = v & ctrl2::TASD.mask();
        kept | ctrl2::RFFN.val(plan.configuration.rffn() as u32) | ctrl2::RRS
    });
    FlexCan::<R>::write_filters(regs, &plan.table);
    // Masks of the transmit mailboxes: a remote-frame mailbox briefly receives after
    // its transmission; exact matching keeps it to its own identifier.
    for n in plan.configuration.primary_filter_capacity()..MESSAGE_BUFFERS as usize {
        regs.write32(regs::rximr(n), u32::MAX);
    }
    let mut tx_flags = 0;
    for mb in plan.configuration.first_remote_mailbox() as usize..=DATA_MAILBOX as usize {
        regs.write32(regs::mb_cs(mb), cs::CODE.val(code::TX_INACTIVE));
        regs.write32(regs::mb_id(mb), 0);
        regs.write32(regs::mb_word0(mb), 0);
        regs.write32(regs::mb_word1(mb), 0);
        tx_flags |= iflag1::buf(mb);
    }
    regs.write32(IFLAG1, u32::MAX);
    regs.write32(IMASK1, iflag1::BUF5I | iflag1::BUF7I | tx_flags);
    if plan.message_buffers > 32 {
        // MB32 and above lie beyond `MAXMB` (15): never flagged, masked anyway.
        regs.write32(IFLAG2, u32::MAX);
        regs.write32(IMASK2, 0);
    }
    handshake::unfreeze(regs, polls)
}

/// Every error `begin` would report for these arguments (ACAN table 5), found
/// without touching any register. [`ConfigErrors::NONE`] when `begin` would proceed.
///
/// A wished bit rate outside the range of the driver's rule ([`Settings::timing_rule`]:
/// 2,500 bit/s to 1 Mbit/s with the default bus clock), which `begin` refuses with
/// [`BeginError::Timing`] before any other check, is reported here as
/// [`ConfigErrors::BIT_RATE_OUT_OF_RANGE`], with every other flag that applies.
///
/// ```
/// use twocan_flexcan::{check, Board, ConfigErrors, Instance, Settings, Target};
///
/// let t36 = Target::new(Board::Teensy36, Instance::Can0);
/// assert_eq!(check(t36, &Settings::new(125_000), &[], &[]), ConfigErrors::NONE);
/// let slow = check(t36, &Settings::new(2_499), &[], &[]);
/// assert!(slow.contains(ConfigErrors::BIT_RATE_OUT_OF_RANGE));
/// // One bit per second above the fastest rate, though 1 ppm from a timing: refused,
/// // as `set_bitrate` refuses it.
/// let fast = check(t36, &Settings::new(1_000_001), &[], &[]);
/// assert_eq!(fast, ConfigErrors::BIT_RATE_OUT_OF_RANGE);
/// ```
pub fn check(
    target: Target,
    settings: &Settings,
    primary: &[Filter],
    secondary: &[Filter],
) -> ConfigErrors {
    match plan(target, settings, primary, secondary) {
        Ok(_) => ConfigErrors::NONE,
        Err(e) => e,
    }
}

impl<R: Registers> FlexCan<R> {
    /// Configures the module `target` over `regs` (ACAN `begin (settings,
    /// primaryFilters, primaryFilterCount, secondaryFilters, secondaryFilterCount)`,
    /// §15.1; empty lists for the shorter forms).
    ///
    /// **Difference from ACAN:** with no filter at all, *no* frame is received (the ID
    /// table is switched to format D, "all frames rejected", Kinetis RM `MCR.IDAM`);
    /// ACAN receives every frame then. Pass [`Filter::pass_all`] to receive everything
    /// (see `docs/differences.md`).
    ///
    /// `sys` reaches the SIM and PORT registers by absolute address (firmware:
    /// [`crate::regs::SystemRegs`], as `Can0::begin` uses; host: [`crate::HostSystem`]).
    /// `regs` may be `&mut M` to keep the registers (a model) after an error.
    pub fn begin<S: Registers>(
        mut regs: R,
        sys: &mut S,
        target: Target,
        settings: &Settings,
        primary: &[Filter],
        secondary: &[Filter],
    ) -> Result<Self, BeginError> {
        if let Some(e) = bitrate_error(settings) {
            return Err(BeginError::Timing(e));
        }
        let plan = plan(target, settings, primary, secondary).map_err(BeginError::Config)?;
        plan.system.apply(sys);
        let polls = settings.handshake_bound();
        configure(&mut regs, &plan, polls)?;
        let bus_mode = if settings.listen_only {
            BusMode::ListenOnly
        } else if settings.loop_back {
            BusMode::LoopBack
        } else {
            BusMode::Normal
        };
        Ok(FlexCan::configured(
            regs,
            target,
            plan.table,
            bus_mode,
            settings.bus_off_recovery,
            polls,
            settings.message_irq_priority,
            plan.system,
            settings.bus_clock_hz.unwrap_or(settings.can_clock.hz()),
        ))
    }
}

#[cfg(all(
    target_os = "none",
    any(feature = "teensy32", feature = "teensy35", feature = "teensy36"),
    not(any(feature = "teensy40", feature = "teensy41"))
))]
mod firmware {
    use twocan_core::Filter;

    use super::*;
    use crate::instance::Can0;
    #[cfg(feature = "teensy36")]
    use crate::instance::Can1;
    use crate::regs::{FlexCanRegs, SystemRegs};

    /// The SIM and PORT registers, addressed absolutely.
    fn system() -> SystemRegs {
        // SAFETY: base 0 with absolute offsets, the window SIM..PORTE: `begin` only
        // touches SIM_SCGC3/5/6 and the PCRs of this instance's pins, read-modify-writes
        // of SIM in a critical section; those registers exist on every Teensy 3.x chip.
        unsafe { SystemRegs::new(0) }
    }

    impl Can0 {
        /// ACAN `ACAN::can0.begin` (§15): configures FlexCAN0 and gives the
        /// controller. On error the token comes back with the reason.
        pub fn begin(
            self,
            settings: &Settings,
            primary: &[Filter],
            secondary: &[Filter],
        ) -> Result<FlexCan<FlexCanRegs>, (Self, BeginError)> {
            let target = self.target();
            // SAFETY: the token is unique (taken once) and consumed here, so this is
            // the only access to FlexCAN0, at its reference-manual base address.
            let regs = unsafe { FlexCanRegs::new(regs::CAN0_BASE) };
            FlexCan::begin(regs, &mut system(), target, settings, primary, secondary)
                .map_err(|e| (self, e))
        }
    }

    #[cfg(feature = "teensy36")]
    impl Can1 {
        /// ACAN `ACAN::can1.begin` (§15): configures FlexCAN1 (Teensy 3.6).
        pub fn begin(
            self,
            settings: &Settings,
            primary: &[Filter],
            secondary: &[Filter],
        ) -> Result<FlexCan<FlexCanRegs>, (Self, BeginError)> {
            let target = self.target();
            // SAFETY: as for `Can0::begin`, for FlexCAN1.
            let regs = unsafe { FlexCanRegs::new(regs::CAN1_BASE) };
            FlexCan::begin(regs, &mut system(), target, settings, primary, secondary)
                .map_err(|e| (self, e))
        }
    }
}
