//! One trait over both controllers, so that the conformance suite, the fault scenarios
//! and the full-load test are written once and run on FlexCAN and on bxCAN.
//!
//! [`Backend`] brings a node of one controller up on the host harness's bus (the real
//! driver over its peripheral model, see `twocan-host`) from backend-neutral
//! [`NodeOptions`]; [`Dut`] is what a test needs from the node afterwards: the portable
//! driver, its interrupt line and the model's own counters (lost and filtered frames),
//! which are counted by the model, independently of the driver.
//!
//! The constants of each implementation are facts of the hardware manuals (FIFO depth,
//! filter capacity, overrun policy, clock), not values read back from the drivers.

use twocan_bxcan::model::BxCanModel;
use twocan_bxcan::{Config as BxConfig, ConfigError, FifoPolicy, PlanError};
use twocan_core::timing::{
    cia_sample_point, solve, Limits, PeripheralClockRule, Timing, TimingError, TimingRule,
    DEFAULT_TOLERANCE_PPM,
};
use twocan_core::{
    BusOffRecovery, Driver, Filter, Hardware, Mode, ModeSupport, Registers, TxPolicy,
};
use twocan_flexcan::filters::OwnedTable;
use twocan_flexcan::layout::{Imxrt1062, Kinetis, Layout};
use twocan_flexcan::model::FlexCanModel;
use twocan_flexcan::options::Full;
use twocan_flexcan::{
    BeginError, Board, CanClock, ConfigErrors, Configuration, FlexCanHw, Instance, Settings, Target,
};
use twocan_host::{
    attach_plain, BxNode, FlexNodeOf, Harness, Serviced, SetupError, RX_RING, STM32F767_APB1_HZ,
    TX_RING,
};
use twocan_sim::{Bus, BusNode, NodeId};

/// How a node leaves bus-off.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Recovery {
    /// By itself after 128 × 11 recessive bits.
    Automatic,
    /// Only when software asks (`Driver::recover`), then after 128 × 11 recessive bits.
    Manual,
}

/// What a receive FIFO does with a valid frame that arrives while it is full.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OverrunPolicy {
    /// The new frame is lost; the stored ones stay (FlexCAN Rx FIFO; bxCAN with RFLM = 1).
    DiscardNew,
    /// The new frame replaces the newest stored one (bxCAN with RFLM = 0).
    OverwriteNewest,
}

/// Backend-neutral node options.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeOptions {
    /// The portable filter list (empty: receive nothing; [`Filter::pass_all`] receives
    /// everything).
    pub filters: Vec<Filter>,
    /// Bus-off recovery.
    pub recovery: Recovery,
    /// Hardware time stamps wanted (bxCAN: TTCM on; FlexCAN always stamps).
    pub timestamps: bool,
}

impl NodeOptions {
    /// `filters`, automatic recovery.
    pub fn filters(filters: &[Filter]) -> Self {
        NodeOptions {
            filters: filters.to_vec(),
            recovery: Recovery::Automatic,
            timestamps: false,
        }
    }

    /// Receive everything, automatic recovery.
    pub fn pass_all() -> Self {
        Self::filters(&[Filter::pass_all()])
    }

    /// With another recovery mode.
    pub fn recovery(mut self, recovery: Recovery) -> Self {
        self.recovery = recovery;
        self
    }

    /// With hardware time stamps on or off (where the backend can turn them off).
    pub fn timestamps(mut self, on: bool) -> Self {
        self.timestamps = on;
        self
    }
}

/// Why a backend refused to bring a node up, in backend-neutral terms.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Refused {
    /// A filter of the list does not conform (bxCAN says which; FlexCAN's `begin` reports
    /// a flag for the whole list: `None`).
    FilterNotConform {
        /// The filter's index in the user's list, when the backend tells.
        index: Option<usize>,
    },
    /// The list needs more hardware filters than the controller has.
    TooManyFilters,
    /// The backend offers no such option.
    Unsupported(&'static str),
    /// Anything else (the backend's error, printed).
    Other(String),
}

/// Why a bit timing was refused, in backend-neutral terms.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimingRefused {
    /// 0 bit/s.
    Zero,
    /// Faster than clock / fewest quanta per bit.
    TooHigh,
    /// Slower than clock / (largest prescaler × most quanta per bit).
    TooLow,
    /// No timing within the tolerance of the wished rate.
    TooFar,
    /// The sample point is not strictly between 50 % and 100 %.
    SamplePoint,
    /// Within the register ranges, but forbidden by a rule of the controller's manual
    /// (FlexCAN: 8 quanta and 16 bus clocks per bit, Kinetis RM "Arbitration and
    /// matching timing").
    ForbiddenByManual,
    /// Another reason.
    Other,
}

/// How a backend changed its bit rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BitrateChange {
    /// Through the portable API: stop, `Driver::set_bitrate`, start; the controller
    /// kept its installed filters (no initialisation, no filter list supplied again).
    FiltersKept,
    /// The controller was configured again from scratch and the filters were installed
    /// again from the lists the application kept (no backend needs this any more).
    FiltersReinstalledFromLists,
}

/// Where the 128 × 11 recessive bits of a manual bus-off recovery are counted from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ManualRecoveryCount {
    /// From the software request (bxCAN: the sequence starts when initialization mode
    /// is left, RM0410 §40.7.6).
    FromRequest,
    /// From bus-off entry; a request after they were seen rejoins after 11 recessive
    /// bits (Kinetis RM, CTRL1.BOFFREC).
    FromBusOff,
}

/// A node of one backend on the harness bus (the device under test).
pub trait Dut: Serviced {
    /// The backend's controller.
    type C: Hardware;
    /// The portable driver.
    fn driver(&mut self) -> &mut Driver<Self::C, RX_RING, TX_RING, RX_RING>;
    /// The portable driver, shared.
    fn driver_ref(&self) -> &Driver<Self::C, RX_RING, TX_RING, RX_RING>;
    /// The node's place on the bus.
    fn bus_id(&self) -> NodeId;
    /// Whether the model raises an interrupt line the driver services.
    fn irq_pending(&self) -> bool;
    /// Frames lost in the hardware receive FIFOs, as the model counts them.
    fn hw_lost(&self) -> u64;
    /// Valid frames no filter accepted, as the model counts them.
    fn filtered_out(&self) -> u64;
    /// The bit rate the timing registers give with the chip's CAN clock (decoded from the
    /// raw register bits with the reference manual's formula).
    fn bitrate_in_registers(&self) -> u32;
}

/// A controller backend, as the cross-controller tests see it.
pub trait Backend {
    /// The node type.
    type Node: Dut + 'static;
    /// For messages.
    const NAME: &'static str;
    /// Frames one receive FIFO holds (Kinetis RM "Rx FIFO": 6; RM0410 §40.7.5: 3).
    const RX_FIFO_DEPTH: usize;
    /// What the receive FIFO used by [`Backend::attach`] does when full.
    const OVERRUN: OverrunPolicy;
    /// Most distinct exact standard-identifier data filters the controller holds
    /// (ACAN table 4: 14 primary + 18 secondary; RM0410: 28 banks × 4 16-bit list ids).
    const MAX_EXACT_STD_FILTERS: usize;
    /// Whether software-started bus-off recovery is offered.
    const MANUAL_RECOVERY: bool;
    /// Where a manual recovery counts its 128 × 11 recessive bits from.
    const MANUAL_RECOVERY_COUNT: ManualRecoveryCount;
    /// Transmit mailboxes of the node [`Backend::attach`] brings up with at most 12
    /// filters (FlexCAN 12/12 partition: MB15 and MB12–MB14, ACAN §11 table 4; bxCAN:
    /// three, RM0410 §40.7.3).
    const TX_MAILBOXES: u8;
    /// Exact standard and extended filters that partition holds (FlexCAN 12/12: 24
    /// format-A elements, one identifier of either format each; bxCAN CAN1 with all 28
    /// banks: four 16-bit or two 32-bit list identifiers per bank).
    const FILTERS_STD_EXT: (u16, u16);
    /// Optional modes (FlexCAN: no one-shot; bxCAN: no triple sampling).
    const MODES: ModeSupport;
    /// Receive queues (FlexCAN: the Rx FIFO; bxCAN: FIFO 0 and FIFO 1).
    const RX_QUEUES: u8;
    /// Time stamp width of the node [`Backend::attach`] brings up (FlexCAN: the 16-bit
    /// free-running timer; bxCAN without TTCM: none).
    const TIMESTAMP_BITS: Option<u8>;
    /// The CAN clock the bit timing is made from (FlexCAN: 16 MHz oscillator; bxCAN:
    /// APB1 of the STM32F767 at 216 MHz, 54 MHz).
    const CLOCK_HZ: u32;
    /// The bit-timing register ranges and the quanta per bit the manual allows (FlexCAN:
    /// the CTRL1 fields with at least 8 quanta, Kinetis RM "Arbitration and matching
    /// timing"; bxCAN: the `CAN_BTR` fields, RM0410 §40.7.7).
    const LIMITS: Limits;
    /// The manual's minimum ratio between the peripheral clock and the bit rate, with
    /// the peripheral clock of the node [`Backend::attach`] brings up (FlexCAN: 16 bus
    /// clocks per bit with 16 message buffers and the Rx FIFO, from the least bus clock
    /// the manual allows, 16 MHz; the RT1062 in its layout: 17 with `MAXMB` 16, from
    /// the driver's rule for that layout, [`layout_rule`]; bxCAN: none).
    const PERIPHERAL_CLOCK: Option<PeripheralClockRule>;
    /// The fastest bit rate the backend accepts: `CLOCK_HZ / LIMITS.min_quanta()`
    /// unless a rule beyond the register ranges forbids it (FlexCAN: 1 Mbit/s, 16 bus
    /// clocks per bit from the least bus clock the manual allows, 16 MHz).
    const FASTEST_BITRATE: u32;
    /// The slowest bit rate the backend accepts, rounded down: the largest prescaler and
    /// the most quanta (FlexCAN 16 MHz / (256 × 25) = 2,500 bit/s; bxCAN 54 MHz /
    /// (1024 × 25) = 2,109.375 bit/s).
    const SLOWEST_BITRATE: u32;
    /// Whether the node [`Backend::attach`] brings up reports wake-up events
    /// (FlexCAN: no, `MCR.WAKMSK`/`SLFWAK` never set, Kinetis RM MCR; bxCAN: yes,
    /// `CAN_IER.WKUIE` among the interrupts, RM0410 §40.8).
    const WAKEUP_EVENTS: bool;
    /// Whether software can read the time stamp counter (Kinetis RM "Free Running Timer
    /// (CANx_TIMER)": yes; RM0410 §40.7.2: the TTCM counter is internal, no).
    const TIMESTAMP_COUNTER_READABLE: bool;

    /// Brings a node up on `h`'s bus at its bit rate.
    fn attach(h: &mut Harness, opts: &NodeOptions) -> Result<Self::Node, Refused> {
        Self::attach_via(h, opts, attach_plain)
    }

    /// Like [`Backend::attach`]; `attach` puts the model on the bus (to wrap it).
    fn attach_via(
        h: &mut Harness,
        opts: &NodeOptions,
        attach: impl FnOnce(&mut Bus, &str, Box<dyn BusNode>) -> NodeId,
    ) -> Result<Self::Node, Refused>;

    /// Checks a bit timing the way an application would configure it: the wished rate
    /// with a sample point in per mille. Gives the actual bit rate.
    fn check_timing(bitrate: u32, sample_point_permille: u16) -> Result<u32, TimingRefused>;

    /// Checks a timing given as counts (with its wished rate) the way an application
    /// would configure it, with the default tolerance (FlexCAN: `Settings::timing` given
    /// to `begin`; bxCAN: `Config::from_timing`). Gives the actual bit rate.
    fn check_given_timing(timing: &Timing) -> Result<u32, TimingRefused>;

    /// Replaces the node's filter list through the receive half (`Driver::set_filters`),
    /// compiled for the partition the node was brought up with.
    fn set_filters(node: &mut Self::Node, filters: &[Filter]) -> Result<(), Refused>;

    /// Moves `node` to the new bus of `h` (at another bit rate, brought to the old bus's
    /// time, `node`'s old bus no longer used) and changes its bit rate to `h`'s.
    fn change_bitrate(
        node: Self::Node,
        opts: &NodeOptions,
        h: &mut Harness,
    ) -> Result<(Self::Node, BitrateChange), Refused>;
}

fn timing_refused(e: TimingError) -> TimingRefused {
    match e {
        TimingError::BitrateZero => TimingRefused::Zero,
        TimingError::BitrateTooHigh => TimingRefused::TooHigh,
        TimingError::BitrateTooLow => TimingRefused::TooLow,
        TimingError::TooFarFromWishedBitrate => TimingRefused::TooFar,
        TimingError::SamplePointOutOfRange => TimingRefused::SamplePoint,
        TimingError::ForbiddenByManual => TimingRefused::ForbiddenByManual,
        _ => TimingRefused::Other,
    }
}

// ---------------------------------------------------------------------------------------
// FlexCAN: can0 of a Teensy 3.6.

/// Which FlexCAN module a [`FlexCanBackendOf`] drives, and the facts that differ between
/// the parts: the module, its CAN clock, the message-buffer layout its programs begin it
/// in, and how the node is begun in that layout. The bit-rate range is not a figure of
/// the part: it is the driver's rule for that layout and clock ([`layout_rule`]).
pub trait FlexPart: 'static {
    /// Name in messages.
    const NAME: &'static str;
    /// The module.
    const TARGET: Target;
    /// The protocol engine clock.
    const CLOCK: CanClock;
    /// The message-buffer layout a program for that board begins the module in
    /// (Teensy 3.x: [`Kinetis`]; Teensy 4.x: [`Imxrt1062`]).
    type Layout: Layout;
    /// Begins the node in [`FlexPart::Layout`] as a program for that board does.
    fn begin_via(
        h: &mut Harness,
        settings: &Settings,
        primary: &[Filter],
        secondary: &[Filter],
        attach: impl FnOnce(&mut Bus, &str, Box<dyn BusNode>) -> NodeId,
    ) -> Result<FlexNodeOf<Self::Layout>, SetupError> {
        FlexNodeOf::<Self::Layout>::begin_via(h, Self::TARGET, settings, primary, secondary, attach)
    }
}

/// The configuration the suite's FlexCAN nodes are begun with when they hold few
/// filters: ACAN's default ([`flexcan_lists_on`]).
const ACAN_DEFAULT: Configuration = Configuration::Filters12_12;

/// The bit-timing rule `begin` applies in the layout `L` from the CAN clock `clock` (no
/// bus clock given: the CAN clock, the least the manuals allow) to a table of
/// `configuration`: the driver's own rule, [`twocan_flexcan::begin::timing_rule_in`] —
/// the 16-buffer rule in ACAN's layout, the rule of the message buffers the
/// configuration takes into matching and arbitration in a layout of more buffers (the
/// ERR005829 reserved mailbox counted; IMXRT1060RM, FlexCAN "Arbitration and matching
/// timing", table "Minimum ratio between peripheral clock frequency and CAN bit
/// rate").
pub const fn layout_rule<L: Layout>(clock: CanClock, configuration: Configuration) -> TimingRule {
    // The driver's own rule (one rule for every entry point), for settings from `clock`
    // with no bus clock given (the bit rate does not enter the rule).
    twocan_flexcan::begin::timing_rule_in::<L>(
        &twocan_flexcan::Settings::with_clock(500_000, clock),
        configuration,
    )
}

/// FlexCAN0 of a Teensy 3.6 (MK66FX1M0, 16 message buffers), 16 MHz oscillator.
pub struct Teensy36Can0;

impl FlexPart for Teensy36Can0 {
    const NAME: &'static str = "FlexCAN (Teensy 3.6 can0)";
    const TARGET: Target = Target::new(Board::Teensy36, Instance::Can0);
    const CLOCK: CanClock = CanClock::Oscillator16MHz;
    type Layout = Kinetis;
}

/// CAN3 of a Teensy 4.1 (i.MX RT1062, 64 message buffers, the CAN FD capable module in
/// classic CAN), the 24 MHz oscillator as CAN clock root, begun in the RT1062 layout
/// ([`Imxrt1062`]) as every Teensy 4 program begins it: the ERR005829 reserved mailbox
/// after the Rx FIFO area, the transmit mailboxes after it.
pub struct Teensy41Can3;

impl FlexPart for Teensy41Can3 {
    const NAME: &'static str = "FlexCAN (Teensy 4.1 CAN3)";
    const TARGET: Target = Target::new(Board::Teensy41, Instance::Can3);
    const CLOCK: CanClock = CanClock::IMXRT_24MHZ;
    type Layout = Imxrt1062;
}

/// CAN1 of a Teensy 4.1 (i.MX RT1062), the 24 MHz oscillator as CAN clock root, in the
/// RT1062 layout ([`Imxrt1062`]): the module the Teensy 4 examples use
/// (`teensy4-loopback-lean`, [`crate::lean`]).
pub struct Teensy41Can1;

impl FlexPart for Teensy41Can1 {
    const NAME: &'static str = "FlexCAN (Teensy 4.1 CAN1)";
    const TARGET: Target = Target::new(Board::Teensy41, Instance::Can1);
    const CLOCK: CanClock = CanClock::IMXRT_24MHZ;
    type Layout = Imxrt1062;
}

/// A FlexCAN module through ACAN's `begin`: the driver is the same for every part, the
/// part is data ([`FlexPart`]).
pub struct FlexCanBackendOf<P: FlexPart>(core::marker::PhantomData<P>);

/// FlexCAN can0 of a Teensy 3.6 through ACAN's `begin`.
pub type FlexCanBackend = FlexCanBackendOf<Teensy36Can0>;

/// CAN3 of a Teensy 4.1 (i.MX RT1062) through the same `begin`: the third configuration
/// of the conformance suite.
pub type Rt1062Backend = FlexCanBackendOf<Teensy41Can3>;

/// The Teensy 3.6 can0 target.
pub fn teensy36_can0() -> Target {
    Target::new(Board::Teensy36, Instance::Can0)
}

/// ACAN settings for `bit_rate` holding `filters`: up to 12 primary filters in ACAN's
/// default 12/12 configuration, more in the 14/18 configuration (14 primary, the rest
/// secondary). Gives the settings and the two lists.
pub fn flexcan_lists(bit_rate: u32, filters: &[Filter]) -> (Settings, Vec<Filter>, Vec<Filter>) {
    flexcan_lists_on(CanClock::Oscillator16MHz, bit_rate, filters)
}

/// [`flexcan_lists`] from the CAN clock `clock`.
pub fn flexcan_lists_on(
    clock: CanClock,
    bit_rate: u32,
    filters: &[Filter],
) -> (Settings, Vec<Filter>, Vec<Filter>) {
    let mut s = Settings::with_clock(bit_rate, clock);
    if filters.len() <= Configuration::Filters12_12.primary_filter_capacity() {
        (s, filters.to_vec(), Vec::new())
    } else {
        s.configuration = Configuration::Filters14_18;
        let n = Configuration::Filters14_18.primary_filter_capacity();
        (s, filters[..n].to_vec(), filters[n..].to_vec())
    }
}

fn flexcan_refused(e: SetupError) -> Refused {
    match e {
        SetupError::FlexCan(BeginError::Config(flags)) => {
            if flags.contains(ConfigErrors::TOO_MANY_PRIMARY_FILTERS)
                || flags.contains(ConfigErrors::TOO_MANY_SECONDARY_FILTERS)
            {
                Refused::TooManyFilters
            } else if flags.contains(ConfigErrors::PRIMARY_FILTER_NOT_CONFORM)
                || flags.contains(ConfigErrors::SECONDARY_FILTER_NOT_CONFORM)
            {
                Refused::FilterNotConform { index: None }
            } else {
                Refused::Other(format!("{flags:?}"))
            }
        }
        other => Refused::Other(format!("{other:?}")),
    }
}

/// Bit rate of FlexCAN `CTRL1` timing bits (Kinetis RM, CTRL1: PRESDIV 31–24, PSEG1 21–19,
/// PSEG2 18–16, PROPSEG 2–0; "Protocol timing": Sclock = clock / (PRESDIV + 1), bit =
/// 1 + (PROPSEG + 1) + (PSEG1 + 1) + (PSEG2 + 1) quanta).
pub fn flexcan_ctrl1_bitrate(ctrl1: u32, clock_hz: u32) -> u32 {
    let presdiv = (ctrl1 >> 24) & 0xFF;
    let pseg1 = (ctrl1 >> 19) & 0x7;
    let pseg2 = (ctrl1 >> 16) & 0x7;
    let propseg = ctrl1 & 0x7;
    let quanta = 1 + (propseg + 1) + (pseg1 + 1) + (pseg2 + 1);
    clock_hz / ((presdiv + 1) * quanta)
}

/// Bit rate of a bxCAN `CAN_BTR` value (RM0410 §40.7.7: tq = (BRP + 1) tPCLK, bit =
/// 1 + (TS1 + 1) + (TS2 + 1) quanta; BRP 9–0, TS1 19–16, TS2 22–20).
pub fn bxcan_btr_bitrate(btr: u32, clock_hz: u32) -> u32 {
    let brp = btr & 0x3FF;
    let ts1 = (btr >> 16) & 0xF;
    let ts2 = (btr >> 20) & 0x7;
    clock_hz / ((brp + 1) * (3 + ts1 + ts2))
}

impl<L: Layout> Dut for FlexNodeOf<L> {
    type C = FlexCanHw<twocan_host::Clocked<FlexCanModel>, Full<L>>;
    fn driver(&mut self) -> &mut Driver<Self::C, RX_RING, TX_RING, RX_RING> {
        &mut self.driver
    }
    fn driver_ref(&self) -> &Driver<Self::C, RX_RING, TX_RING, RX_RING> {
        &self.driver
    }
    fn bus_id(&self) -> NodeId {
        self.id
    }
    fn irq_pending(&self) -> bool {
        self.model.irq_pending()
    }
    fn hw_lost(&self) -> u64 {
        self.model.frames_lost()
    }
    fn filtered_out(&self) -> u64 {
        self.model.frames_discarded()
    }
    fn bitrate_in_registers(&self) -> u32 {
        let clock = self.driver.hardware().capabilities().clock_hz;
        flexcan_ctrl1_bitrate(self.model.peek32(twocan_flexcan::regs::CTRL1), clock)
    }
}

impl<P: FlexPart> FlexCanBackendOf<P> {
    /// The rule `begin` applies to the node [`Backend::attach`] brings up (ACAN's
    /// default configuration in the part's layout, [`layout_rule`]).
    pub const RULE: TimingRule = layout_rule::<P::Layout>(P::CLOCK, ACAN_DEFAULT);
}

impl<P: FlexPart> Backend for FlexCanBackendOf<P> {
    type Node = FlexNodeOf<P::Layout>;
    const NAME: &'static str = P::NAME;
    const RX_FIFO_DEPTH: usize = 6;
    const OVERRUN: OverrunPolicy = OverrunPolicy::DiscardNew;
    const MAX_EXACT_STD_FILTERS: usize = 14 + 18;
    const MANUAL_RECOVERY: bool = true;
    const MANUAL_RECOVERY_COUNT: ManualRecoveryCount = ManualRecoveryCount::FromBusOff;
    const TX_MAILBOXES: u8 = 4;
    const FILTERS_STD_EXT: (u16, u16) = (24, 24);
    const MODES: ModeSupport = ModeSupport {
        loop_back: true,
        listen_only: true,
        one_shot: false,
        triple_sampling: true,
        manual_recovery: true,
        timestamps: true,
    };
    const RX_QUEUES: u8 = 1;
    const TIMESTAMP_BITS: Option<u8> = Some(16);
    const CLOCK_HZ: u32 = P::CLOCK.hz();
    const LIMITS: Limits = Self::RULE.limits;
    const PERIPHERAL_CLOCK: Option<PeripheralClockRule> = Self::RULE.peripheral_clock;
    const FASTEST_BITRATE: u32 = Self::RULE.max_bitrate();
    const SLOWEST_BITRATE: u32 = Self::RULE.min_bitrate();
    const WAKEUP_EVENTS: bool = false;
    const TIMESTAMP_COUNTER_READABLE: bool = true;

    fn attach_via(
        h: &mut Harness,
        opts: &NodeOptions,
        attach: impl FnOnce(&mut Bus, &str, Box<dyn BusNode>) -> NodeId,
    ) -> Result<Self::Node, Refused> {
        let rate = h.bus().borrow().bit_rate();
        let (mut s, primary, secondary) = flexcan_lists_on(P::CLOCK, rate, &opts.filters);
        s.bus_off_recovery = portable_recovery(opts.recovery);
        P::begin_via(h, &s, &primary, &secondary, attach).map_err(flexcan_refused)
    }

    fn check_timing(bitrate: u32, sample_point_permille: u16) -> Result<u32, TimingRefused> {
        // An application's settings for that rate and sample point (the solver within
        // the limits the driver accepts), given to `begin`.
        let t = solve(
            P::CLOCK.hz(),
            bitrate,
            &Self::RULE.limits,
            sample_point_permille,
        )
        .map_err(timing_refused)?;
        Self::check_given_timing(&t)
    }

    fn check_given_timing(timing: &Timing) -> Result<u32, TimingRefused> {
        let mut s = Settings::with_clock(timing.bitrate, P::CLOCK);
        s.timing = *timing;
        let model = FlexCanModel::new(P::TARGET.model_chip());
        let r = twocan_flexcan::FlexCan::<_, P::Layout>::begin_with_layout(
            twocan_flexcan::IdleClocked::new(model),
            &mut twocan_flexcan::HostSystem::new(),
            P::TARGET,
            &s,
            &[Filter::pass_all()],
            &[],
        );
        let flags = twocan_flexcan::begin::check_with_layout::<P::Layout>(
            P::TARGET,
            &s,
            &[Filter::pass_all()],
            &[],
        );
        match r {
            Ok(_) => {
                assert_eq!(flags, ConfigErrors::NONE, "check() and begin() agree");
                Ok(s.actual_bit_rate())
            }
            Err(BeginError::Timing(e)) => {
                assert!(flags.contains(ConfigErrors::BIT_RATE_OUT_OF_RANGE));
                Err(timing_refused(e))
            }
            Err(BeginError::Config(f)) => {
                assert_eq!(f, flags, "check() and begin() agree");
                if f.contains(ConfigErrors::BIT_RATE_TOO_FAR) {
                    Err(TimingRefused::TooFar)
                } else if f == ConfigErrors::BIT_TIMING_FORBIDDEN {
                    Err(TimingRefused::ForbiddenByManual)
                } else {
                    Err(TimingRefused::Other)
                }
            }
            Err(BeginError::Hardware(e)) => panic!("begin: {e:?}"),
        }
    }

    fn set_filters(node: &mut Self::Node, filters: &[Filter]) -> Result<(), Refused> {
        let c = node.driver.hardware().configuration();
        let n = filters.len().min(c.primary_filter_capacity());
        // The table of the node's layout, compiled as `begin` compiles it.
        let (primary, secondary) = (&filters[..n], &filters[n..]);
        let flags = <P::Layout as Layout>::Table::check_lists(c, primary, secondary);
        if flags != ConfigErrors::NONE {
            return Err(flexcan_refused(SetupError::FlexCan(BeginError::Config(
                flags,
            ))));
        }
        let table = <P::Layout as Layout>::Table::build_lists(c, primary, secondary);
        node.driver
            .set_filters(&table)
            .map_err(|e| Refused::Other(format!("{e:?}")))
    }

    fn change_bitrate(
        node: Self::Node,
        _opts: &NodeOptions,
        h: &mut Harness,
    ) -> Result<(Self::Node, BitrateChange), Refused> {
        let FlexNodeOf { model, driver, .. } = node;
        let rate = h.bus().borrow().bit_rate();
        let (driver, id) = portable_bitrate_change(driver, rate, h, |hw, h| {
            hw.registers_mut().set_bus(h.bus());
            h.bus()
                .borrow_mut()
                .attach(&format!("{}-moved", P::NAME), model.clone())
        })?;
        Ok((FlexNodeOf { model, driver, id }, BitrateChange::FiltersKept))
    }
}

// ---------------------------------------------------------------------------------------
// bxCAN: CAN1 of an STM32F767.

/// bxCAN CAN1 of an STM32F767 with every filter bank (`CAN2SB = 28`), transmit FIFO
/// order, one receive FIFO (FIFO 0), RFLM = 0, every interrupt.
pub struct BxCanBackend;

/// The bxCAN configuration [`BxCanBackend`] uses for `bit_rate`.
pub fn bxcan_config(bit_rate: u32, recovery: Recovery) -> Result<BxConfig, ConfigError> {
    BxConfig::from_bitrate(STM32F767_APB1_HZ, bit_rate)?
        .tx_policy(TxPolicy::Fifo)
        .recovery(portable_recovery(recovery))
        .interrupts(twocan_bxcan::config::DEFAULT_INTERRUPTS)
        .can2_start_bank(28)
}

fn bxcan_refused(e: SetupError) -> Refused {
    match e {
        SetupError::BxCanPlan(PlanError::Filter { index, .. }) => Refused::FilterNotConform {
            index: Some(index as usize),
        },
        SetupError::BxCanPlan(
            PlanError::TooManyBanks { .. } | PlanError::TooManyFilters { .. },
        ) => Refused::TooManyFilters,
        other => Refused::Other(format!("{other:?}")),
    }
}

impl Dut for BxNode {
    type C = twocan_bxcan::BxCan<twocan_host::Clocked<BxCanModel>>;
    fn driver(&mut self) -> &mut Driver<Self::C, RX_RING, TX_RING, RX_RING> {
        &mut self.driver
    }
    fn driver_ref(&self) -> &Driver<Self::C, RX_RING, TX_RING, RX_RING> {
        &self.driver
    }
    fn bus_id(&self) -> NodeId {
        self.id
    }
    fn irq_pending(&self) -> bool {
        self.model.irq_lines().any()
    }
    fn hw_lost(&self) -> u64 {
        let s = self.model.state();
        s.overruns[0] + s.overruns[1]
    }
    fn filtered_out(&self) -> u64 {
        self.model.state().dropped
    }
    fn bitrate_in_registers(&self) -> u32 {
        bxcan_btr_bitrate(
            self.model.read32(twocan_bxcan::regs::BTR),
            STM32F767_APB1_HZ,
        )
    }
}

impl Backend for BxCanBackend {
    type Node = BxNode;
    const NAME: &'static str = "bxCAN (STM32F767 CAN1)";
    const RX_FIFO_DEPTH: usize = 3;
    const OVERRUN: OverrunPolicy = OverrunPolicy::OverwriteNewest;
    const MAX_EXACT_STD_FILTERS: usize = 28 * 4;
    const MANUAL_RECOVERY: bool = true;
    const MANUAL_RECOVERY_COUNT: ManualRecoveryCount = ManualRecoveryCount::FromRequest;
    const TX_MAILBOXES: u8 = 3;
    const FILTERS_STD_EXT: (u16, u16) = (28 * 4, 28 * 2);
    const MODES: ModeSupport = ModeSupport {
        loop_back: true,
        listen_only: true,
        one_shot: true,
        triple_sampling: false,
        manual_recovery: true,
        timestamps: true,
    };
    const RX_QUEUES: u8 = 2;
    const TIMESTAMP_BITS: Option<u8> = None;
    const CLOCK_HZ: u32 = 54_000_000;
    const LIMITS: Limits = Limits::BXCAN;
    const PERIPHERAL_CLOCK: Option<PeripheralClockRule> = None;
    const FASTEST_BITRATE: u32 = STM32F767_APB1_HZ / 3;
    const SLOWEST_BITRATE: u32 = STM32F767_APB1_HZ / (1024 * 25);
    const WAKEUP_EVENTS: bool = true;
    const TIMESTAMP_COUNTER_READABLE: bool = false;

    fn attach_via(
        h: &mut Harness,
        opts: &NodeOptions,
        attach: impl FnOnce(&mut Bus, &str, Box<dyn BusNode>) -> NodeId,
    ) -> Result<BxNode, Refused> {
        let rate = h.bus().borrow().bit_rate();
        let config = bxcan_config(rate, opts.recovery)
            .map_err(|e| Refused::Other(format!("{e:?}")))?
            .timestamps(opts.timestamps);
        BxNode::with_config_via(h, &config, &opts.filters, FifoPolicy::Fifo0, attach)
            .map_err(bxcan_refused)
    }

    fn check_timing(bitrate: u32, sample_point_permille: u16) -> Result<u32, TimingRefused> {
        let c = BxConfig::from_bitrate_with(
            STM32F767_APB1_HZ,
            bitrate,
            sample_point_permille,
            DEFAULT_TOLERANCE_PPM,
        )
        .map_err(|e| match e {
            ConfigError::Timing(t) => timing_refused(t),
            _ => TimingRefused::Other,
        })?;
        Ok(bxcan_btr_bitrate(c.btr_value(), STM32F767_APB1_HZ))
    }

    fn check_given_timing(timing: &Timing) -> Result<u32, TimingRefused> {
        let c = BxConfig::from_timing(*timing, DEFAULT_TOLERANCE_PPM).map_err(|e| match e {
            ConfigError::Timing(t) => timing_refused(t),
            _ => TimingRefused::Other,
        })?;
        Ok(bxcan_btr_bitrate(c.btr_value(), STM32F767_APB1_HZ))
    }

    fn set_filters(node: &mut BxNode, filters: &[Filter]) -> Result<(), Refused> {
        let plan = node
            .driver
            .hardware()
            .plan(filters, FifoPolicy::Fifo0)
            .map_err(|e| bxcan_refused(SetupError::BxCanPlan(e)))?;
        node.driver
            .set_filters(&plan)
            .map_err(|e| Refused::Other(format!("{e:?}")))
    }

    fn change_bitrate(
        node: BxNode,
        _opts: &NodeOptions,
        h: &mut Harness,
    ) -> Result<(BxNode, BitrateChange), Refused> {
        let BxNode { model, driver, .. } = node;
        let rate = h.bus().borrow().bit_rate();
        let (driver, id) = portable_bitrate_change(driver, rate, h, |hw, h| {
            hw.registers_mut().set_bus(h.bus());
            h.bus()
                .borrow_mut()
                .attach("stm32f767-can1-moved", model.clone())
        })?;
        Ok((BxNode { model, driver, id }, BitrateChange::FiltersKept))
    }
}

/// The portable recovery setting of a test's [`Recovery`].
pub fn portable_recovery(r: Recovery) -> BusOffRecovery {
    match r {
        Recovery::Automatic => BusOffRecovery::Automatic,
        Recovery::Manual => BusOffRecovery::Manual,
    }
}

/// Stop → `Driver::set_bitrate` → start, through the portable API only. Between stop and
/// start the harness moves the model to the new bus (`relocate`: the simulated bus has
/// one bit rate; the controller is taken out of the driver and put back unchanged).
#[allow(clippy::type_complexity)]
fn portable_bitrate_change<H: Hardware>(
    mut driver: Driver<H, RX_RING, TX_RING, RX_RING>,
    rate: u32,
    h: &mut Harness,
    relocate: impl FnOnce(&mut H, &mut Harness) -> NodeId,
) -> Result<(Driver<H, RX_RING, TX_RING, RX_RING>, NodeId), Refused> {
    driver
        .set_mode(Mode::Stopped)
        .map_err(|e| Refused::Other(format!("stop: {e:?}")))?;
    let sp = cia_sample_point(rate);
    driver
        .set_bitrate(rate, sp)
        .map_err(|e| Refused::Other(format!("set_bitrate: {e:?}")))?;
    let mut hw = driver.release();
    let id = relocate(&mut hw, h);
    let mut driver = Driver::new(hw);
    driver
        .set_mode(Mode::Normal)
        .map_err(|e| Refused::Other(format!("start: {e:?}")))?;
    Ok((driver, id))
}

/// A new harness at `bit_rate` whose bus time is already `now` (nothing attached yet),
/// to move nodes onto.
pub fn harness_at(bit_rate: u32, now: u64) -> Harness {
    let h = Harness::new(bit_rate).expect("bus");
    h.bus().borrow_mut().run_until(now);
    assert_eq!(h.now(), now);
    h
}
