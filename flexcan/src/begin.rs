//! `begin`: check everything, then configure the module (ACAN §15).
//!
//! [`check`] computes every error flag of ACAN table 5 at once without any
//! hardware access. [`FlexCan::begin`] runs the same check and returns
//! [`BeginError::Config`] before writing any register; only valid settings reach the
//! hardware, in the order of the Kinetis reference manuals' "FlexCAN initialization
//! sequence":
//!
//! The bit timing is judged by the driver's one rule ([`timing_rule_in`],
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
//!    format A, 16 MBs — with the RT1062 layout, up to the data mailbox: `MAXMB`, IMXRT1060RM
//!    MCR field MAXMB —, warnings), `CTRL1` (bit timing, listen-only, loop-back,
//!    automatic bus-off recovery, error interrupt masks), `CTRL2` (`RFFN`, remote frames stored), the ID filter
//!    table, `RXIMR`, `RXFGMASK`, the transmit mailboxes inactive, flags cleared,
//!    `IMASK1` (FIFO frames available and overflow, every transmit mailbox; with the
//!    RT1062 layout's transmit mailboxes above MB31, `IMASK2` for them, IMXRT1060RM
//!    "Interrupt Masks 2 register (IMASK2)");
//! 5. leave freeze (wait `FRZACK` and `NOTRDY` to clear), then wait until the module
//!    is synchronised to the bus (`ESR1.SYNCH`, 11 recessive bits; internal in
//!    loop-back mode): when `begin` returns, a frame starting on the bus is received.
//!
//! Every wait is bounded by [`Settings::handshake_bound`]; a missing acknowledge is
//! [`BeginError::Hardware`]`(`[`Error::Timeout`]`)`.

use core::mem::MaybeUninit;

use twocan_core::timing::{TimingError, TimingRule};
use twocan_core::{BusMode, BusOffRecovery, Error, Filter, LastErrorCode, Mode, Registers};

use crate::begin_error::{BeginError, ConfigErrors};
use crate::can_clock::CanClock;
use crate::configuration::{Configuration, DATA_MAILBOX, MESSAGE_BUFFERS};
use crate::controller::FlexCan;
use crate::filters::OwnedTable;
use crate::handshake;
use crate::imxrt::ImxrtPlan;
use crate::installed::PlannedTable;
use crate::instance::Target;
use crate::layout::{layout_accepts, Kinetis, Layout};
use crate::options::Options;
use crate::regs::{
    self, code, cs, ctrl1, ctrl2, iflag1, mcr, CTRL1, CTRL2, IFLAG1, IFLAG2, IMASK1, IMASK2, MCR,
};
use crate::settings::Settings;
use crate::split::{FlexCanHw, Parts};
use crate::system::{choose_pins, LayoutSystem, PortPlan, SystemPlan};

/// Everything `begin` will write but the filter table, computed before anything is
/// written (the lists are checked; the table is built once, inside the controller
/// `begin` returns, so that no table-sized value moves through the configuration).
#[derive(Debug, Clone)]
struct Plan {
    system: SystemPlan,
    mcr: u32,
    ctrl1: u32,
    configuration: Configuration,
    /// The module's message buffers (16 or 64, [`crate::Chip::message_buffers`]).
    message_buffers: usize,
}

/// The timing rule `begin` applies to `settings` for a table of `configuration` in the
/// layout `L` — the one rule of every entry point (`begin`, `check`, `BeginPlan`, the
/// capabilities, `set_timing`, `set_bitrate`): the CTRL1 ranges, at least 8 quanta per
/// bit, and the bus clocks per CAN bit the message buffers in matching and arbitration
/// need (`MCR[MAXMB]` + 1: 16 buffers in the Kinetis layout, 16 clocks per bit; in the
/// RT1062 layout the buffers the configuration uses with the ERR005829 reserved mailbox,
/// 17 clocks up to 32 buffers and 30 above — Kinetis RM and IMXRT1060RM "Arbitration and
/// matching timing"), from the settings' CAN clock and bus clock
/// ([`Settings::bus_clock_hz`]; unset: the CAN clock itself).
pub const fn timing_rule_in<L: Layout>(
    settings: &Settings,
    configuration: Configuration,
) -> TimingRule {
    rule_in::<L>(
        settings.can_clock.hz(),
        settings.bus_clock_hz,
        configuration,
    )
}

/// [`timing_rule_in`] from the clocks (the running controller keeps no `Settings`).
pub(crate) const fn rule_in<L: Layout>(
    can_clock_hz: u32,
    bus_clock_hz: Option<u32>,
    configuration: Configuration,
) -> TimingRule {
    if L::IFLAG2 {
        crate::settings::timing_rule_for_buffers(
            can_clock_hz,
            bus_clock_hz,
            configuration.message_buffers_used_in(L::E5829),
        )
    } else {
        crate::settings::timing_rule_for(can_clock_hz, bus_clock_hz)
    }
}

/// The checks of ACAN table 5, all of them, then the register values; the
/// configuration against the layout `L` and the chip ([`layout_accepts`]:
/// [`ConfigErrors::CONFIGURATION_NOT_ON_CHIP`]).
const fn plan<L: Layout>(
    target: Target,
    settings: &Settings,
    configuration: Configuration,
    filter_errors: ConfigErrors,
) -> Result<Plan, ConfigErrors> {
    let mut errors = timing_errors(&timing_rule_in::<L>(settings, configuration), settings);
    let timing_bits = settings.timing.flexcan_ctrl1();
    if timing_bits.is_err() {
        errors = errors.union(ConfigErrors::BIT_TIMING_INCONSISTENT);
    }

    errors = errors.union(filter_errors);

    let chip = target.board.chip();
    // Every chip has the 16 buffers of the layout without `IFLAG2` (a constant); a
    // layout of more buffers needs the chip to have every one it uses
    // (`Layout::accepts`, the same rule).
    let accepted = if L::IFLAG2 {
        layout_accepts(L::MAX_RFFN, L::IFLAG2, L::E5829, chip, configuration)
    } else {
        configuration.rffn() <= L::MAX_RFFN
    };
    if !accepted {
        errors = errors.union(ConfigErrors::CONFIGURATION_NOT_ON_CHIP);
    }
    // One layout per chip: the RT1062 is begun in its own layout only (the ERR005829
    // workaround, `Layout::E5829`), the Kinetis parts in theirs (the RT1062 layout needs
    // more buffers than they have: `CONFIGURATION_NOT_ON_CHIP` above).
    if chip.is_imxrt() && !L::E5829 {
        errors = errors.union(ConfigErrors::LAYOUT_NOT_FOR_CHIP);
    }
    if !settings.can_clock.fits(chip) {
        errors = errors.union(ConfigErrors::CLOCK_NOT_ON_CHIP);
    }
    let system = match (chip.is_imxrt(), target.clock_gate()) {
        (_, None) => {
            errors = errors.union(ConfigErrors::NO_SUCH_INSTANCE);
            None
        }
        (true, Some(gate)) => imxrt_system(target, gate, settings, &mut errors),
        (false, Some(gate)) => kinetis_system(target, gate, settings, &mut errors),
    };

    match (errors.is_empty(), timing_bits, system) {
        (true, Ok(timing_bits), Some(system)) => {
            let mut mcr = mcr::FRZ
                | mcr::HALT
                | mcr::RFEN
                | mcr::IRMQ
                | mcr::AEN
                | mcr::IDAM.val(mcr::IDAM_FORMAT_A)
                | mcr::MAXMB.val(last_mailbox::<L>(configuration) as u32);
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
            if matches!(settings.bus_off_recovery, BusOffRecovery::Manual) {
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
                configuration,
                message_buffers: chip.message_buffers(),
            })
        }
        _ => Err(errors),
    }
}

/// The last message buffer the driver enables (`MCR[MAXMB]`) and its data mailbox:
/// MB15 with [`Kinetis`] (a constant), [`Configuration::data_mailbox_in`] with a layout
/// of more buffers (IMXRT1060RM, MCR field MAXMB; after the ERR005829 reserved mailbox
/// with [`Layout::E5829`]).
#[inline(always)]
pub(crate) const fn last_mailbox<L: Layout>(configuration: Configuration) -> usize {
    if L::IFLAG2 {
        configuration.data_mailbox_in(L::E5829) as usize
    } else {
        DATA_MAILBOX as usize
    }
}

/// The Kinetis SIM/PORT plan: the pins of ACAN §7 (alternates on request).
const fn kinetis_system(
    target: Target,
    gate: (usize, u32),
    settings: &Settings,
    errors: &mut ConfigErrors,
) -> Option<SystemPlan> {
    let Some(pins) = target.board.pins(target.instance) else {
        return None;
    };
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
                *errors = errors.union(ConfigErrors::NO_ALTERNATE_TX_PIN);
            }
            if no_rx {
                *errors = errors.union(ConfigErrors::NO_ALTERNATE_RX_PIN);
            }
            None
        }
    }
}

/// The RT1062 CCM/IOMUXC plan: the board's one pin pair (no alternates on the Teensy
/// 4.x, so asking for one is [`ConfigErrors::NO_ALTERNATE_TX_PIN`] /
/// [`ConfigErrors::NO_ALTERNATE_RX_PIN`]), the clock root of the settings.
const fn imxrt_system(
    target: Target,
    gate: (usize, u32),
    settings: &Settings,
    errors: &mut ConfigErrors,
) -> Option<SystemPlan> {
    let Some(pins) = target.board.imx_pins(target.instance) else {
        return None;
    };
    if settings.use_alternate_tx_pin {
        *errors = errors.union(ConfigErrors::NO_ALTERNATE_TX_PIN);
    }
    if settings.use_alternate_rx_pin {
        *errors = errors.union(ConfigErrors::NO_ALTERNATE_RX_PIN);
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
const fn timing_errors(rule: &TimingRule, settings: &Settings) -> ConfigErrors {
    let mut errors = ConfigErrors::NONE;
    match rule.check_bitrate(settings.wished_bit_rate()) {
        Ok(()) => {}
        Err(TimingError::ForbiddenByManual) => {
            errors = errors.union(ConfigErrors::BIT_TIMING_FORBIDDEN)
        }
        Err(_) => errors = errors.union(ConfigErrors::BIT_RATE_OUT_OF_RANGE),
    }
    if !settings.bit_rate_close_to_wished() {
        errors = errors.union(ConfigErrors::BIT_RATE_TOO_FAR);
    }
    match rule.check_timing(&settings.timing) {
        Ok(()) => {}
        Err(TimingError::ForbiddenByManual) => {
            errors = errors.union(ConfigErrors::BIT_TIMING_FORBIDDEN)
        }
        Err(_) => errors = errors.union(ConfigErrors::BIT_TIMING_INCONSISTENT),
    }
    errors
}

/// The error `begin` gives before any other check: the wished rate outside the range of
/// the driver's rule ([`TimingRule::check_bitrate`]; a rule that accepts nothing is left
/// to the flags, [`ConfigErrors::BIT_TIMING_FORBIDDEN`]).
const fn bitrate_error<L: Layout>(
    settings: &Settings,
    configuration: Configuration,
) -> Option<TimingError> {
    match timing_rule_in::<L>(settings, configuration).check_bitrate(settings.wished_bit_rate()) {
        Ok(()) | Err(TimingError::ForbiddenByManual) => None,
        Err(e) => Some(e),
    }
}

/// Writes the plan, and the filter table with `write_table` (steps 2–5 of the module
/// docs).
fn configure<R: Registers, L: Layout>(
    regs: &mut R,
    plan: &Plan,
    write_table: impl FnOnce(&R),
    polls: u32,
) -> Result<(), Error> {
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
    write_table(regs);
    // Masks of the transmit mailboxes: a remote-frame mailbox briefly receives after
    // its transmission; exact matching keeps it to its own identifier.
    let data = last_mailbox::<L>(plan.configuration);
    let last = if L::IFLAG2 {
        data
    } else {
        MESSAGE_BUFFERS as usize - 1
    };
    let first = if L::E5829 {
        plan.configuration.first_remote_mailbox_in(true)
    } else {
        plan.configuration.first_remote_mailbox()
    } as usize;
    let primary = if L::IFLAG2 {
        plan.configuration.primary_filter_capacity()
    } else {
        // Below RFFN 4 the individual masks are the FIFO's message buffers.
        first
    };
    for n in primary..last + 1 {
        regs.write32(regs::rximr(n), u32::MAX);
    }
    // The transmit mailboxes' flags: IFLAG1 bit n for MBn, or (above MB31, where every
    // transmit mailbox of the configuration lies: `Configuration::data_mailbox`) IFLAG2
    // bit n - 32 (IMXRT1060RM, IMASK2/IFLAG2).
    let base = tx_flag_base::<L>(data);
    if L::E5829 {
        // ERR005829 (i.MX RT1060 chip errata): the first valid mailbox after the Rx
        // FIFO area is a transmit mailbox kept INACTIVE, inside `MAXMB`, its interrupt
        // masked (no bit in `IMASK1`/`IMASK2`); so are the buffers between it and the
        // transmit mailboxes when these start at MB32 (`first_remote_mailbox_in`).
        // Message buffer RAM is not reset by a soft reset: each gets its code here.
        for mb in plan.configuration.reserved_mailbox() as usize..first {
            regs.write32(regs::mb_cs(mb), cs::CODE.val(code::TX_INACTIVE));
        }
    }
    let mut tx_flags = 0;
    for mb in first..=data {
        regs.write32(regs::mb_cs(mb), cs::CODE.val(code::TX_INACTIVE));
        regs.write32(regs::mb_id(mb), 0);
        regs.write32(regs::mb_word0(mb), 0);
        regs.write32(regs::mb_word1(mb), 0);
        tx_flags |= iflag1::buf(mb - base);
    }
    regs.write32(IFLAG1, u32::MAX);
    let (low, high) = if base == 0 {
        (tx_flags, 0)
    } else {
        (0, tx_flags)
    };
    regs.write32(IMASK1, RX_FIFO_IMASK | low);
    if plan.message_buffers > 32 {
        // MB32 and above: the transmit mailboxes of the RT1062's larger tables, or
        // beyond `MAXMB` (never flagged, masked anyway).
        regs.write32(IFLAG2, u32::MAX);
        regs.write32(IMASK2, high);
    }
    handshake::unfreeze(regs, polls)
}

/// The Rx FIFO's enables in `IMASK1` as `begin` writes them: frames available
/// (`BUF5I`) and overflow (`BUF7I`); the warning (`BUF6I`) stays masked (Kinetis RM,
/// "Rx FIFO": with the FIFO on, IMASK1 bits 5–7 enable its three flags).
pub(crate) const RX_FIFO_IMASK: u32 = iflag1::BUF5I | iflag1::BUF7I;

/// The first message buffer of the flag register that holds the transmit mailboxes'
/// flags, the data mailbox being `data`: 0 (`IFLAG1`), or 32 (`IFLAG2`) for a data
/// mailbox above MB31 with a layout that has `IFLAG2` (a constant 0 otherwise).
#[inline(always)]
pub(crate) const fn tx_flag_base<L: Layout>(data: usize) -> usize {
    if L::IFLAG2 && data >= 32 {
        32
    } else {
        0
    }
}

/// Every error `begin` would report for these arguments (ACAN table 5), found
/// without touching any register, in the layout of the target's chip (the only one
/// `begin` takes there: [`crate::layout::Kinetis`] on a Teensy 3.x,
/// [`crate::layout::Imxrt1062`] on a Teensy 4.x, [`ConfigErrors::LAYOUT_NOT_FOR_CHIP`]).
/// [`ConfigErrors::NONE`] when `begin` would proceed.
///
/// A wished bit rate outside the range of the driver's rule ([`timing_rule_in`]:
/// 2,500 bit/s to 1 Mbit/s with the default bus clock on a Teensy 3.x), which `begin` refuses with
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
    // The layout of the target's chip (the only one `begin` takes there).
    if target.board.chip().is_imxrt() {
        check_with_layout::<crate::layout::Imxrt1062>(target, settings, primary, secondary)
    } else {
        check_with_layout::<Kinetis>(target, settings, primary, secondary)
    }
}

/// [`check`] for a controller of the layout `L` ([`crate::layout`]): what
/// [`FlexCan::begin_with_layout`] would report.
///
/// ```
/// use twocan_core::Filter;
/// use twocan_flexcan::begin::check_with_layout;
/// use twocan_flexcan::layout::{Imxrt1062, Kinetis};
/// use twocan_flexcan::{check, Board, CanClock, ConfigErrors, Configuration, Instance};
/// use twocan_flexcan::{Settings, Target};
///
/// let t41 = Target::new(Board::Teensy41, Instance::Can1);
/// let mut s = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
/// s.configuration = Configuration::Filters32_96;
/// let secondary: Vec<Filter> = (0..96).map(|i| Filter::standard(0x100 + i)).collect();
/// assert_eq!(check_with_layout::<Imxrt1062>(t41, &s, &[], &secondary), ConfigErrors::NONE);
/// // `check` takes the target chip's layout: the same answer.
/// assert_eq!(check(t41, &s, &[], &secondary), ConfigErrors::NONE);
/// // The Kinetis layout is not the RT1062's: a typed error, nothing written.
/// let kinetis = check_with_layout::<Kinetis>(t41, &s, &[], &secondary);
/// assert!(kinetis.contains(ConfigErrors::LAYOUT_NOT_FOR_CHIP));
/// ```
pub fn check_with_layout<L: Layout>(
    target: Target,
    settings: &Settings,
    primary: &[Filter],
    secondary: &[Filter],
) -> ConfigErrors {
    let filters = L::Table::check_lists(settings.configuration, primary, secondary);
    match plan::<L>(target, settings, settings.configuration, filters) {
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
        regs: R,
        sys: &mut S,
        target: Target,
        settings: &Settings,
        primary: &[Filter],
        secondary: &[Filter],
    ) -> Result<Self, BeginError> {
        Self::begin_with_layout(regs, sys, target, settings, primary, secondary)
    }

    /// [`FlexCan::begin`] compiling the lists straight into `slot`, a table in a
    /// `static` ([`crate::filters::TableSlot`]), and giving the split controller with
    /// the options `O` ([`crate::options::FullInSlot`]) that keeps the reference: every
    /// feature of [`FlexCan::begin`] + [`FlexCan::into_split`] (filter switches, time
    /// stamps), without a table-sized value on the configuration's stack or in the
    /// driver state. On an error the slot comes back with it (to try again).
    ///
    /// ```
    /// use twocan_core::Filter;
    /// use twocan_flexcan::filters::TableSlot;
    /// use twocan_flexcan::options::FullInSlot;
    /// use twocan_flexcan::{Board, FlexCan, FlexCanHw, HostSystem, Instance, Settings, Target};
    /// use twocan_flexcan::{model::FlexCanModel, IdleClocked};
    ///
    /// static TABLE: TableSlot = TableSlot::new();
    /// let model = IdleClocked::new(FlexCanModel::mk66fx1m0());
    /// let target = Target::new(Board::Teensy36, Instance::Can0);
    /// let hw: FlexCanHw<_, FullInSlot> = FlexCan::begin_in(
    ///     model,
    ///     &mut HostSystem::new(),
    ///     target,
    ///     &Settings::new(500_000),
    ///     &[Filter::standard(0x100)],
    ///     &[],
    ///     TABLE.take().unwrap(),
    /// )
    /// .map_err(|(e, _)| format!("{e:?}"))?;
    /// # let _ = hw;
    /// # Ok::<(), String>(())
    /// ```
    #[allow(clippy::type_complexity)]
    pub fn begin_in<S: Registers, O, L>(
        regs: R,
        sys: &mut S,
        target: Target,
        settings: &Settings,
        primary: &[Filter],
        secondary: &[Filter],
        slot: &'static mut L::Table,
    ) -> Result<FlexCanHw<R, O>, (BeginError, &'static mut L::Table)>
    where
        L: Layout,
        O: Options<Layout = L, Table = &'static mut L::Table>,
    {
        let (regs, table, parts) =
            Self::begin_in_parts::<S, L>(regs, sys, target, settings, primary, secondary, slot)?;
        Ok(FlexCanHw::from_parts(regs, target, table, parts))
    }

    /// [`FlexCan::begin_in`] writing the split controller **in place** into `hw`
    /// (the storage a `static` state lends: `twocan_core::split::State::split_with`,
    /// `rt::IrqState::start_in_place`), with the settings checked beforehand
    /// ([`BeginPlan`]: at compile time for `const` settings, or before the state lends
    /// its storage), so that neither the table nor the controller moves through the
    /// configuration and the checks do not deepen it. The lists are checked against
    /// the plan's configuration ([`BeginError::Config`] with the filter flags) and
    /// compiled into `slot`. Returns the controller written; on an error nothing is
    /// written and the table's slot comes back.
    #[allow(clippy::type_complexity)]
    #[inline(always)]
    pub fn begin_in_place<'h, S: Registers, O, L>(
        hw: &'h mut MaybeUninit<FlexCanHw<R, O>>,
        mut regs: R,
        sys: &mut S,
        checked: &BeginPlan<L>,
        primary: &[Filter],
        secondary: &[Filter],
        slot: &'static mut L::Table,
    ) -> Result<&'h mut FlexCanHw<R, O>, (BeginError, &'static mut L::Table)>
    where
        L: Layout,
        O: Options<Layout = L, Table = &'static mut L::Table>,
    {
        let plan = &checked.plan;
        let filters = L::Table::check_lists(plan.configuration, primary, secondary);
        if filters != ConfigErrors::NONE {
            return Err((BeginError::Config(filters), slot));
        }
        let parts = match checked.parts() {
            Ok(p) => p,
            Err(e) => return Err((e, slot)),
        };
        if let Err(e) = plan.system.apply(sys) {
            return Err((BeginError::Config(e), slot));
        }
        slot.fill_lists(plan.configuration, primary, secondary);
        let table: &L::Table = slot;
        if let Err(e) = configure::<R, L>(
            &mut regs,
            plan,
            |r| FlexCan::<R, L>::write_filters(r, table),
            checked.polls,
        ) {
            return Err((BeginError::Hardware(e), slot));
        }
        Ok(hw.write(FlexCanHw::from_parts(regs, checked.target, slot, parts)))
    }

    /// [`FlexCan::begin_in`] but the controller: the checks, the lists compiled into
    /// `slot`, the module configured; the split controller's small values.
    #[allow(clippy::type_complexity)]
    fn begin_in_parts<S: Registers, L: Layout>(
        mut regs: R,
        sys: &mut S,
        target: Target,
        settings: &Settings,
        primary: &[Filter],
        secondary: &[Filter],
        slot: &'static mut L::Table,
    ) -> Result<(R, &'static mut L::Table, Parts<L::System>), (BeginError, &'static mut L::Table)>
    {
        if let Some(e) = bitrate_error::<L>(settings, settings.configuration) {
            return Err((BeginError::Timing(e), slot));
        }
        let filters = L::Table::check_lists(settings.configuration, primary, secondary);
        let plan = match plan::<L>(target, settings, settings.configuration, filters) {
            Ok(p) => p,
            Err(e) => return Err((BeginError::Config(e), slot)),
        };
        let Some(system) = L::System::from_plan(&plan.system) else {
            return Err((BeginError::Config(ConfigErrors::LAYOUT_NOT_FOR_CHIP), slot));
        };
        if let Err(e) = plan.system.apply(sys) {
            return Err((BeginError::Config(e), slot));
        }
        let polls = settings.handshake_bound();
        slot.fill_lists(plan.configuration, primary, secondary);
        let table: &L::Table = slot;
        if let Err(e) = configure::<R, L>(
            &mut regs,
            &plan,
            |r| FlexCan::<R, L>::write_filters(r, table),
            polls,
        ) {
            return Err((BeginError::Hardware(e), slot));
        }
        let parts = Parts {
            bus_mode: bus_mode_of(settings),
            recovery: settings.bus_off_recovery,
            polls,
            irq_priority: settings.message_irq_priority,
            mode: Mode::Normal,
            last_error: LastErrorCode::None,
            system,
            bus_clock_hz: settings.bus_clock_hz.unwrap_or(settings.can_clock.hz()),
        };
        Ok((regs, slot, parts))
    }

    /// `begin` with a filter table planned at compile time ([`crate::const_plan!`],
    /// [`crate::filters::SizedTable::planned`]), straight to the split controller with
    /// the options `O` ([`crate::options::Lean`], or a firmware's own whose table is a
    /// [`PlannedTable`]): no filter list is checked or compiled at run time and no
    /// table-sized value is built — the controller keeps a few words pointing into the
    /// plan, whose elements and masks are written as [`FlexCan::begin`] writes a
    /// compiled list's. The plan's configuration replaces `settings.configuration`.
    /// The same checks of the settings as `begin` (ACAN table 5, the filter flags
    /// aside: the plan fits by construction), the same initialization sequence.
    ///
    /// ```
    /// use twocan_core::Filter;
    /// use twocan_flexcan::options::Lean;
    /// use twocan_flexcan::planner::PlanOptions;
    /// use twocan_flexcan::{const_plan, Board, FlexCan, FlexCanHw, HostSystem, Instance};
    /// use twocan_flexcan::{model::FlexCanModel, IdleClocked, Settings, Target};
    ///
    /// const FILTERS: [Filter; 2] = [Filter::standard(0x100), Filter::extended(0x1234)];
    /// let plan = const_plan!(FILTERS, PlanOptions::choose()).planned();
    /// // The model, its clock running while the driver waits for an acknowledge.
    /// let model = IdleClocked::new(FlexCanModel::mk66fx1m0());
    /// let target = Target::new(Board::Teensy36, Instance::Can0);
    /// let mut settings = Settings::new(500_000);
    /// settings.loop_back = true;
    /// let hw: FlexCanHw<_, Lean> =
    ///     FlexCan::begin_planned(model, &mut HostSystem::new(), target, &settings, plan)
    ///         .map_err(|e| format!("{e:?}"))?;
    /// assert_eq!(hw.configuration(), plan.configuration());
    /// # Ok::<(), String>(())
    /// ```
    pub fn begin_planned<S: Registers, O: Options<Table = PlannedTable>>(
        regs: R,
        sys: &mut S,
        target: Target,
        settings: &Settings,
        table: PlannedTable,
    ) -> Result<FlexCanHw<R, O>, BeginError> {
        let checked =
            BeginPlan::<O::Layout>::new_with_layout(target, settings, table.configuration())?;
        Self::begin_checked(regs, sys, &checked, table)
    }

    /// [`FlexCan::begin_planned`] with the settings checked beforehand ([`BeginPlan`]):
    /// with a `const` plan of `const` settings, no check of the settings links into the
    /// firmware — `begin` is the initialization sequence alone. `table` must be planned
    /// for the configuration `checked` was made for ([`Error::InvalidArgument`]
    /// otherwise, nothing written).
    pub fn begin_checked<S: Registers, O: Options<Table = PlannedTable>>(
        regs: R,
        sys: &mut S,
        checked: &BeginPlan<O::Layout>,
        table: PlannedTable,
    ) -> Result<FlexCanHw<R, O>, BeginError> {
        let (regs, parts) = Self::begin_checked_parts(regs, sys, checked, table)?;
        Ok(FlexCanHw::from_parts(regs, checked.target, table, parts))
    }

    /// [`FlexCan::begin_checked`] writing the split controller **in place** into `hw`
    /// (see [`FlexCan::begin_in_place`]). On an error nothing is written.
    #[inline(always)]
    pub fn begin_checked_in_place<'h, S: Registers, O: Options<Table = PlannedTable>>(
        hw: &'h mut MaybeUninit<FlexCanHw<R, O>>,
        regs: R,
        sys: &mut S,
        checked: &BeginPlan<O::Layout>,
        table: PlannedTable,
    ) -> Result<&'h mut FlexCanHw<R, O>, BeginError> {
        let (regs, parts) = Self::begin_checked_parts(regs, sys, checked, table)?;
        Ok(hw.write(FlexCanHw::from_parts(regs, checked.target, table, parts)))
    }

    /// What [`FlexCan::begin_checked`] and [`FlexCan::begin_checked_in_place`] share.
    #[inline(always)]
    fn begin_checked_parts<S: Registers, L: Layout>(
        mut regs: R,
        sys: &mut S,
        checked: &BeginPlan<L>,
        table: PlannedTable,
    ) -> Result<(R, Parts<L::System>), BeginError> {
        let plan = &checked.plan;
        if table.configuration() != plan.configuration {
            return Err(BeginError::Hardware(Error::InvalidArgument));
        }
        let parts = checked.parts()?;
        plan.system.apply(sys).map_err(BeginError::Config)?;
        configure::<R, L>(
            &mut regs,
            plan,
            |r| {
                FlexCan::<R, L>::write_table(
                    r,
                    table.rejects_all(),
                    table.elements(),
                    table.individual_masks(),
                    table.global_mask(),
                )
            },
            checked.polls,
        )?;
        Ok((regs, parts))
    }
}

impl<R: Registers, L: Layout> FlexCan<R, L> {
    /// [`FlexCan::begin`] for the message-buffer layout `L` ([`crate::layout`]): with
    /// [`crate::layout::Imxrt1062`] on an RT1062, `settings.configuration` may be any
    /// RFFN up to 0xF (a table of up to 128 elements, 32 primary and 96 secondary
    /// filters; the ERR005829 reserved mailbox and the transmit mailboxes after it,
    /// [`Configuration::data_mailbox_in`]); a
    /// configuration the layout or the chip does not take is
    /// [`ConfigErrors::CONFIGURATION_NOT_ON_CHIP`], nothing written.
    ///
    /// ```
    /// use twocan_core::Filter;
    /// use twocan_flexcan::layout::Imxrt1062;
    /// use twocan_flexcan::{model::FlexCanModel, Board, CanClock, Configuration, FlexCan};
    /// use twocan_flexcan::{HostSystem, IdleClocked, Instance, Settings, Target};
    ///
    /// let target = Target::new(Board::Teensy41, Instance::Can1);
    /// let mut settings = Settings::with_clock(500_000, CanClock::IMXRT_24MHZ);
    /// settings.configuration = Configuration::Filters32_96;
    /// settings.loop_back = true;
    /// let secondary: Vec<Filter> = (0..96).map(|i| Filter::extended(0x1000 + i)).collect();
    /// let model = IdleClocked::new(FlexCanModel::new(target.model_chip()));
    /// let can = FlexCan::<_, Imxrt1062>::begin_with_layout(
    ///     model, &mut HostSystem::new(), target, &settings, &[], &secondary,
    /// )
    /// .map_err(|e| format!("{e:?}"))?;
    /// assert_eq!(can.filters().elements().len(), 128);
    /// # Ok::<(), String>(())
    /// ```
    pub fn begin_with_layout<S: Registers>(
        regs: R,
        sys: &mut S,
        target: Target,
        settings: &Settings,
        primary: &[Filter],
        secondary: &[Filter],
    ) -> Result<Self, BeginError> {
        if let Some(e) = bitrate_error::<L>(settings, settings.configuration) {
            return Err(BeginError::Timing(e));
        }
        let filters = L::Table::check_lists(settings.configuration, primary, secondary);
        let plan = plan::<L>(target, settings, settings.configuration, filters)
            .map_err(BeginError::Config)?;
        let system = L::System::from_plan(&plan.system)
            .ok_or(BeginError::Config(ConfigErrors::LAYOUT_NOT_FOR_CHIP))?;
        plan.system.apply(sys).map_err(BeginError::Config)?;
        let polls = settings.handshake_bound();
        let bus_mode = bus_mode_of(settings);
        // The table is built once, in the controller, and written from there.
        let mut controller = FlexCan::configured(
            regs,
            target,
            L::Table::build_lists(plan.configuration, primary, secondary),
            bus_mode,
            settings.bus_off_recovery,
            polls,
            settings.message_irq_priority,
            system,
            settings.bus_clock_hz.unwrap_or(settings.can_clock.hz()),
        );
        let table = &controller.table;
        configure::<R, L>(
            &mut controller.regs,
            &plan,
            |r| FlexCan::<R, L>::write_filters(r, table),
            polls,
        )?;
        Ok(controller)
    }
}

/// What `begin` writes for `settings` on `target` with a table planned for a
/// configuration, every check of ACAN table 5 done (the filter flags aside): made once,
/// by a `const fn`, so that `const` settings are checked at compile time
/// ([`BeginPlan::new_or_panic`]) and [`FlexCan::begin_checked`] links no check.
///
/// ```
/// use twocan_flexcan::begin::BeginPlan;
/// use twocan_flexcan::{Board, Configuration, Instance, Settings, Target};
///
/// const T36: Target = Target::new(Board::Teensy36, Instance::Can0);
/// const CHECKED: BeginPlan =
///     BeginPlan::new_or_panic(T36, &Settings::new(500_000), Configuration::Filters8_0);
/// assert!(BeginPlan::new(T36, &Settings::new(2_000_000), Configuration::Filters8_0).is_err());
/// # let _ = CHECKED;
/// ```
///
/// The plan is made for a message-buffer layout `L` ([`crate::layout`], [`Kinetis`] by
/// default: [`BeginPlan::new`]; [`BeginPlan::new_with_layout`] for another), the layout
/// of the options of the controller it configures.
#[derive(Debug, Clone)]
pub struct BeginPlan<L: Layout = Kinetis> {
    layout: core::marker::PhantomData<L>,
    target: Target,
    plan: Plan,
    polls: u32,
    bus_mode: BusMode,
    recovery: BusOffRecovery,
    irq_priority: u8,
    bus_clock_hz: u32,
}

impl BeginPlan {
    /// The checks `begin` makes of `settings` on `target` (ACAN table 5 and the bit-rate
    /// range first, as [`FlexCan::begin`]), and the register values, for a table of
    /// `configuration` (which replaces `settings.configuration`).
    pub const fn new(
        target: Target,
        settings: &Settings,
        configuration: Configuration,
    ) -> Result<Self, BeginError> {
        Self::new_with_layout(target, settings, configuration)
    }

    /// [`BeginPlan::new`], panicking on an error: in a `const` item, settings that
    /// `begin` would refuse are a compile-time error.
    pub const fn new_or_panic(
        target: Target,
        settings: &Settings,
        configuration: Configuration,
    ) -> Self {
        Self::new_with_layout_or_panic(target, settings, configuration)
    }
}

impl<L: Layout> BeginPlan<L> {
    /// [`BeginPlan::new`] for the layout `L` (a configuration the layout or the chip does
    /// not take: [`ConfigErrors::CONFIGURATION_NOT_ON_CHIP`]).
    pub const fn new_with_layout(
        target: Target,
        settings: &Settings,
        configuration: Configuration,
    ) -> Result<Self, BeginError> {
        if let Some(e) = bitrate_error::<L>(settings, configuration) {
            return Err(BeginError::Timing(e));
        }
        match plan::<L>(target, settings, configuration, ConfigErrors::NONE) {
            Ok(plan) => Ok(BeginPlan {
                layout: core::marker::PhantomData,
                target,
                plan,
                polls: settings.handshake_bound(),
                bus_mode: bus_mode_of(settings),
                recovery: settings.bus_off_recovery,
                irq_priority: settings.message_irq_priority,
                bus_clock_hz: match settings.bus_clock_hz {
                    Some(hz) => hz,
                    None => settings.can_clock.hz(),
                },
            }),
            Err(e) => Err(BeginError::Config(e)),
        }
    }

    /// [`BeginPlan::new_with_layout`], panicking on an error (in a `const` item: a
    /// compile-time error).
    pub const fn new_with_layout_or_panic(
        target: Target,
        settings: &Settings,
        configuration: Configuration,
    ) -> Self {
        match Self::new_with_layout(target, settings, configuration) {
            Ok(p) => p,
            Err(BeginError::Timing(_)) => {
                panic!("twocan_flexcan::BeginPlan: bit rate outside the driver's range")
            }
            Err(_) => panic!("twocan_flexcan::BeginPlan: settings refused (ACAN table 5)"),
        }
    }

    /// The configuration the plan is made for.
    pub const fn configuration(&self) -> Configuration {
        self.plan.configuration
    }

    /// The module the plan is made for.
    pub const fn target(&self) -> Target {
        self.target
    }

    /// The split controller's small values, as the module is right after `begin`
    /// (a plan of the other chip family: [`ConfigErrors::LAYOUT_NOT_FOR_CHIP`], which
    /// [`BeginPlan::new_with_layout`] already refuses).
    #[inline(always)]
    fn parts(&self) -> Result<Parts<L::System>, BeginError> {
        let Some(system) = L::System::from_plan(&self.plan.system) else {
            return Err(BeginError::Config(ConfigErrors::LAYOUT_NOT_FOR_CHIP));
        };
        Ok(Parts {
            bus_mode: self.bus_mode,
            recovery: self.recovery,
            polls: self.polls,
            irq_priority: self.irq_priority,
            mode: Mode::Normal,
            last_error: LastErrorCode::None,
            system,
            bus_clock_hz: self.bus_clock_hz,
        })
    }
}

/// The bus mode the settings ask for (ACAN §4: listen-only, loop-back).
const fn bus_mode_of(settings: &Settings) -> BusMode {
    if settings.listen_only {
        BusMode::ListenOnly
    } else if settings.loop_back {
        BusMode::LoopBack
    } else {
        BusMode::Normal
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
    crate::token_begin::token_begin!(Can0, system);
    crate::token_begin::token_end!(Can0, system);
    #[cfg(feature = "teensy36")]
    crate::token_begin::token_begin!(Can1, system);
    #[cfg(feature = "teensy36")]
    crate::token_begin::token_end!(Can1, system);
}
