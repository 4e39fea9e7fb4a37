//! Filter banks: the hardware form of acceptance filters, direct bank configuration, the
//! filter match index (FMI) numbering and a reference evaluator of the hardware rules.
//!
//! Rules used here (lecture notes after RM0410 §40.7.4 "Identifier filtering"):
//! - a bank holds one 32-bit or two 16-bit filters (`FSCi`), in identifier-mask or
//!   identifier-list mode (`FBMi`), so it contributes 1 (32-bit mask), 2 (32-bit list,
//!   16-bit mask) or 4 (16-bit list) filter numbers;
//! - register layout (figure "Filter bank scale configuration"): 32-bit words are
//!   `STID[10:0]|EXID[17:0] IDE RTR 0` (the layout of `CAN_RIxR`); 16-bit words are
//!   `STID[10:0] RTR IDE EXID[17:15]`; in 16-bit mask mode the low half-word of `FiRx` is
//!   the identifier and the high half-word its mask; in 16-bit list mode the four
//!   half-words `FiR1[15:0]`, `FiR1[31:16]`, `FiR2[15:0]`, `FiR2[31:16]` are filters
//!   n..n+3;
//! - numbering ("Filter match index"): per FIFO, in bank order, each bank contributing its
//!   1, 2 or 4 numbers whether it is active or not;
//! - priority ("Filter priority rules"): a 32-bit filter beats a 16-bit one, then list
//!   beats mask, then the lower filter number wins.
//!
//! A bank is described by [`Bank`]; [`FilterPlan`] (the [`twocan_core::Hardware::Filters`]
//! of this backend) holds the banks of one instance and the map from each FIFO's match
//! index back to the index the application uses ([`twocan_core::RxFrame::filter`]).
//! The automatic planner ([`crate::planner`]) builds a plan from portable
//! [`Filter`]s; [`FilterPlan::manual`] and [`FilterPlan::set_bank`] configure banks
//! directly.

use twocan_core::filter_set::{key, key_parts, lower_bound, Key, KeyTable};
use twocan_core::{Filter, FilterError, Format, Frame, FrameKind};

use crate::regs::{firx, FILTER_BANKS};

/// Receive FIFO (notes "Reception handling"; `FFAi` selects it per bank).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Fifo {
    /// FIFO 0 (`FFAi = 0`).
    #[default]
    Fifo0,
    /// FIFO 1 (`FFAi = 1`).
    Fifo1,
}

impl Fifo {
    /// 0 or 1.
    pub const fn index(self) -> usize {
        match self {
            Fifo::Fifo0 => 0,
            Fifo::Fifo1 => 1,
        }
    }
}

/// The scale and mode of a bank (`FSCi`, `FBMi`; notes "Filter bank scale and mode
/// configuration").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BankKind {
    /// One 32-bit identifier/mask pair (`FSC = 1`, `FBM = 0`): 1 filter number.
    Mask32,
    /// Two 32-bit identifiers (`FSC = 1`, `FBM = 1`): 2 filter numbers.
    List32,
    /// Two 16-bit identifier/mask pairs (`FSC = 0`, `FBM = 0`, the reset state): 2 numbers.
    Mask16,
    /// Four 16-bit identifiers (`FSC = 0`, `FBM = 1`): 4 filter numbers.
    List16,
}

impl BankKind {
    /// How many filter numbers (FMI values) the bank contributes to its FIFO's numbering.
    pub const fn slots(self) -> usize {
        match self {
            BankKind::Mask32 => 1,
            BankKind::List32 | BankKind::Mask16 => 2,
            BankKind::List16 => 4,
        }
    }

    /// `FSCi`: single 32-bit scale.
    pub const fn is_32bit(self) -> bool {
        matches!(self, BankKind::Mask32 | BankKind::List32)
    }

    /// `FBMi`: identifier-list mode.
    pub const fn is_list(self) -> bool {
        matches!(self, BankKind::List32 | BankKind::List16)
    }

    /// Hardware priority class of the bank's filters ("Filter priority rules"): 0 wins
    /// over 1, ... (32-bit list, 32-bit mask, 16-bit list, 16-bit mask).
    pub const fn priority_class(self) -> u8 {
        match self {
            BankKind::List32 => 0,
            BankKind::Mask32 => 1,
            BankKind::List16 => 2,
            BankKind::Mask16 => 3,
        }
    }
}

/// Why a filter cannot be put in a bank slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BankError {
    /// The filter does not conform (can-core [`Filter::check`]).
    Filter {
        /// The slot (0-based within the bank).
        slot: u8,
        /// Why.
        error: FilterError,
    },
    /// The filter accepts frames that the slot cannot tell apart exactly: a list slot
    /// takes one identifier of one format and one kind; a 16-bit slot only sees
    /// `STID[10:0]`/`EXID[28:18]`, `EXID[17:15]`, IDE and RTR.
    NotRepresentable {
        /// The slot (0-based within the bank).
        slot: u8,
    },
}

/// One filter bank as written to `FS1R`/`FM1R`/`FFA1R`/`FA1R` and `FiR1`/`FiR2`
/// (notes "Filter bank scale and mode configuration", figure "Filter bank configuration
/// & register organization").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Bank {
    /// Scale and mode.
    pub kind: BankKind,
    /// The FIFO receiving the frames it accepts.
    pub fifo: Fifo,
    /// `FACTi`. A deactivated bank accepts nothing but still counts in the numbering.
    pub active: bool,
    /// `FiR1`.
    pub fr1: u32,
    /// `FiR2`.
    pub fr2: u32,
}

/// The 32-bit filter word of a frame (`STID|EXID IDE RTR 0`, as `CAN_RIxR`).
pub const fn frame_word32(raw_id: u32, extended: bool, remote: bool) -> u32 {
    let rtr = if remote { firx::RTR } else { 0 };
    if extended {
        (raw_id << 3) | firx::IDE | rtr
    } else {
        (raw_id << 21) | rtr
    }
}

/// The 16-bit filter word of a frame (`STID[10:0] RTR IDE EXID[17:15]`): an extended
/// identifier contributes its 14 most significant bits only.
pub const fn frame_word16(raw_id: u32, extended: bool, remote: bool) -> u16 {
    let rtr = if remote { firx::RTR16 } else { 0 };
    let w = if extended {
        (((raw_id >> 18) & 0x7FF) << 5) | firx::IDE16 | ((raw_id >> 15) & 0x7)
    } else {
        (raw_id & 0x7FF) << 5
    };
    (w | rtr) as u16
}

/// The identifier bits a 16-bit filter compares, in extended-identifier position.
pub const EXT_BITS_IN_16BIT: u32 = 0x1FFF_8000;

/// RTR value and whether RTR is compared, for a frame kind.
const fn kind_bits(kind: FrameKind) -> (bool, bool) {
    match kind {
        FrameKind::Data => (false, true),
        FrameKind::Remote => (true, true),
        FrameKind::Any => (false, false),
    }
}

/// The 32-bit identifier/mask pair accepting exactly the frames `f` accepts. Every
/// conforming filter has one.
pub const fn mask32_of(f: &Filter) -> (u32, u32) {
    let (rtr, rtr_cmp) = kind_bits(f.kind);
    let mut v = if rtr { firx::RTR } else { 0 };
    let mut m = if rtr_cmp { firx::RTR } else { 0 };
    match f.format {
        Format::Standard => {
            // Standard frames have EXID = 0 in the word; the mask leaves those bits out.
            v |= f.id << 21;
            m |= (f.mask << 21) | firx::IDE;
        }
        Format::Extended => {
            v |= (f.id << 3) | firx::IDE;
            m |= (f.mask << 3) | firx::IDE;
        }
        Format::Any => {}
    }
    (v, m)
}

/// The 16-bit identifier/mask pair accepting exactly the frames `f` accepts, if any:
/// standard filters, format-free filters (zero mask), and extended filters whose mask
/// compares no bit below `EXID[15]`.
pub const fn mask16_of(f: &Filter) -> Option<(u16, u16)> {
    let (rtr, rtr_cmp) = kind_bits(f.kind);
    let mut v: u32 = if rtr { firx::RTR16 } else { 0 };
    let mut m: u32 = if rtr_cmp { firx::RTR16 } else { 0 };
    match f.format {
        Format::Standard => {
            v |= (f.id & 0x7FF) << 5;
            m |= ((f.mask & 0x7FF) << 5) | firx::IDE16;
        }
        Format::Extended => {
            if f.mask & !EXT_BITS_IN_16BIT != 0 {
                return None;
            }
            v |= (((f.id >> 18) & 0x7FF) << 5) | firx::IDE16 | ((f.id >> 15) & 7);
            m |= (((f.mask >> 18) & 0x7FF) << 5) | firx::IDE16 | ((f.mask >> 15) & 7);
        }
        Format::Any => {}
    }
    Some((v as u16, m as u16))
}

/// The single 32-bit list word of `f`, if `f` accepts exactly one (identifier, format,
/// kind).
pub const fn list32_of(f: &Filter) -> Option<u32> {
    let remote = match f.kind {
        FrameKind::Data => false,
        FrameKind::Remote => true,
        FrameKind::Any => return None,
    };
    match f.format {
        Format::Standard if f.mask == 0x7FF => Some(frame_word32(f.id, false, remote)),
        Format::Extended if f.mask == 0x1FFF_FFFF => Some(frame_word32(f.id, true, remote)),
        _ => None,
    }
}

/// The single 16-bit list word of `f`, if `f` accepts exactly the frames of one 16-bit
/// word: one standard identifier, or the extended identifiers sharing their 14 top bits
/// (mask exactly [`EXT_BITS_IN_16BIT`]); one kind.
pub const fn list16_of(f: &Filter) -> Option<u16> {
    let remote = match f.kind {
        FrameKind::Data => false,
        FrameKind::Remote => true,
        FrameKind::Any => return None,
    };
    match f.format {
        Format::Standard if f.mask == 0x7FF => Some(frame_word16(f.id, false, remote)),
        Format::Extended if f.mask == EXT_BITS_IN_16BIT => Some(frame_word16(f.id, true, remote)),
        _ => None,
    }
}

const fn check(f: &Filter, slot: u8) -> Result<(), BankError> {
    match f.check() {
        Ok(()) => Ok(()),
        Err(error) => Err(BankError::Filter { slot, error }),
    }
}

const fn half(low: u16, high: u16) -> u32 {
    (low as u32) | ((high as u32) << 16)
}

impl Bank {
    /// A bank from raw register values (no check: any value is a valid bank).
    pub const fn raw(kind: BankKind, fifo: Fifo, fr1: u32, fr2: u32) -> Bank {
        Bank {
            kind,
            fifo,
            active: true,
            fr1,
            fr2,
        }
    }

    /// A deactivated bank in the reset configuration (16-bit mask, FIFO 0): accepts
    /// nothing, counts two numbers in FIFO 0.
    pub const fn unused() -> Bank {
        Bank {
            kind: BankKind::Mask16,
            fifo: Fifo::Fifo0,
            active: false,
            fr1: 0,
            fr2: 0,
        }
    }

    /// One 32-bit identifier/mask filter accepting exactly what `f` accepts.
    pub const fn mask32(f: &Filter, fifo: Fifo) -> Result<Bank, BankError> {
        if let Err(e) = check(f, 0) {
            return Err(e);
        }
        let (v, m) = mask32_of(f);
        Ok(Bank::raw(BankKind::Mask32, fifo, v, m))
    }

    /// Two 32-bit identifiers; each filter must accept exactly one identifier of one
    /// format and one kind.
    pub const fn list32(a: &Filter, b: &Filter, fifo: Fifo) -> Result<Bank, BankError> {
        let wa = match Self::list32_slot(a, 0) {
            Ok(w) => w,
            Err(e) => return Err(e),
        };
        let wb = match Self::list32_slot(b, 1) {
            Ok(w) => w,
            Err(e) => return Err(e),
        };
        Ok(Bank::raw(BankKind::List32, fifo, wa, wb))
    }

    const fn list32_slot(f: &Filter, slot: u8) -> Result<u32, BankError> {
        if let Err(e) = check(f, slot) {
            return Err(e);
        }
        match list32_of(f) {
            Some(w) => Ok(w),
            None => Err(BankError::NotRepresentable { slot }),
        }
    }

    /// Two 16-bit identifier/mask filters (see [`mask16_of`] for what fits).
    pub const fn mask16(a: &Filter, b: &Filter, fifo: Fifo) -> Result<Bank, BankError> {
        let (va, ma) = match Self::mask16_slot(a, 0) {
            Ok(p) => p,
            Err(e) => return Err(e),
        };
        let (vb, mb) = match Self::mask16_slot(b, 1) {
            Ok(p) => p,
            Err(e) => return Err(e),
        };
        Ok(Bank::raw(
            BankKind::Mask16,
            fifo,
            half(va, ma),
            half(vb, mb),
        ))
    }

    const fn mask16_slot(f: &Filter, slot: u8) -> Result<(u16, u16), BankError> {
        if let Err(e) = check(f, slot) {
            return Err(e);
        }
        match mask16_of(f) {
            Some(p) => Ok(p),
            None => Err(BankError::NotRepresentable { slot }),
        }
    }

    /// Four 16-bit identifiers (see [`list16_of`] for what fits).
    pub const fn list16(f: [&Filter; 4], fifo: Fifo) -> Result<Bank, BankError> {
        let mut w = [0u16; 4];
        let mut i = 0;
        while i < 4 {
            if let Err(e) = check(f[i], i as u8) {
                return Err(e);
            }
            w[i] = match list16_of(f[i]) {
                Some(x) => x,
                None => return Err(BankError::NotRepresentable { slot: i as u8 }),
            };
            i += 1;
        }
        Ok(Bank::raw(
            BankKind::List16,
            fifo,
            half(w[0], w[1]),
            half(w[2], w[3]),
        ))
    }

    /// The same bank, deactivated (`FACTi = 0`).
    pub const fn deactivated(self) -> Bank {
        Bank {
            active: false,
            ..self
        }
    }

    /// Whether filter `slot` of this bank (numbered as the notes' figure: `n`, `n+1`, ...)
    /// accepts the frame `(raw_id, extended, remote)`, active or not.
    pub const fn slot_matches(
        &self,
        slot: usize,
        raw_id: u32,
        extended: bool,
        remote: bool,
    ) -> bool {
        match self.kind {
            BankKind::Mask32 => {
                slot == 0 && (frame_word32(raw_id, extended, remote) ^ self.fr1) & self.fr2 == 0
            }
            BankKind::List32 => {
                let w = frame_word32(raw_id, extended, remote);
                (slot == 0 && w == self.fr1) || (slot == 1 && w == self.fr2)
            }
            BankKind::Mask16 => {
                let reg = match slot {
                    0 => self.fr1,
                    1 => self.fr2,
                    _ => return false,
                };
                let w = frame_word16(raw_id, extended, remote) as u32;
                (w ^ (reg & 0xFFFF)) & (reg >> 16) == 0
            }
            BankKind::List16 => {
                let w = frame_word16(raw_id, extended, remote) as u32;
                let v = match slot {
                    0 => self.fr1 & 0xFFFF,
                    1 => self.fr1 >> 16,
                    2 => self.fr2 & 0xFFFF,
                    3 => self.fr2 >> 16,
                    _ => return false,
                };
                w == v
            }
        }
    }
}

/// Why a plan could not be built or changed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlanError {
    /// A user filter does not conform.
    Filter {
        /// Its index in the user's list.
        index: u16,
        /// Why.
        error: FilterError,
    },
    /// More filters than the planner takes.
    TooManyFilters {
        /// Filters given.
        given: u16,
        /// The most the planner takes ([`crate::planner::MAX_FILTERS`]).
        max: u16,
    },
    /// The filters need more banks than the instance has.
    TooManyBanks {
        /// Banks the smallest exact plan needs (after merging).
        needed: u16,
        /// Banks available to the instance.
        available: u8,
    },
    /// CAN1's and CAN2's lists together need more than the 28 banks of the shared block
    /// ([`crate::planner::plan_dual`]).
    DualTooManyBanks {
        /// Banks CAN1's list needs.
        can1_needed: u16,
        /// Banks CAN2's list needs.
        can2_needed: u16,
        /// Banks of the block.
        available: u8,
    },
    /// The plan's merged or superset slots leave more identifiers to the thread-side
    /// lookup than the plan or the driver keeps (`K` of [`FilterPlan<K>`] or of the
    /// controller, [`LOOKUP_KEYS`] by default): refused at planning time when no plan
    /// within the capacity fits the banks, or when a plan is installed in a controller
    /// with less room.
    TooManyLookupKeys {
        /// Identifiers that would need the lookup.
        needed: u16,
        /// The lookup capacity.
        max: u16,
    },
    /// The plan numbers more match indices in a FIFO than the controller's map holds
    /// (its `M`, sized for a smaller plan: [`PlanRef::match_indices`]).
    TooManyMatchIndices {
        /// Match indices the plan numbers in its busier FIFO.
        needed: u16,
        /// The map's room per FIFO.
        max: u16,
    },
    /// A bank index beyond the filter block (0..28).
    BankOutOfRange,
}

/// A message built in `const` code (for a compile-time error that names the counts).
struct Message {
    buf: [u8; 160],
    len: usize,
}

impl Message {
    const fn new() -> Self {
        Message {
            buf: [0; 160],
            len: 0,
        }
    }

    const fn text(mut self, s: &str) -> Self {
        let b = s.as_bytes();
        let mut i = 0;
        while i < b.len() && self.len < self.buf.len() {
            self.buf[self.len] = b[i];
            self.len += 1;
            i += 1;
        }
        self
    }

    const fn number(mut self, mut n: u32) -> Self {
        let mut digits = [0u8; 10];
        let mut k = 0;
        loop {
            digits[k] = b'0' + (n % 10) as u8;
            k += 1;
            n /= 10;
            if n == 0 {
                break;
            }
        }
        while k > 0 && self.len < self.buf.len() {
            k -= 1;
            self.buf[self.len] = digits[k];
            self.len += 1;
        }
        self
    }

    const fn as_str(&self) -> &str {
        match core::str::from_utf8(self.buf.split_at(self.len).0) {
            Ok(s) => s,
            Err(_) => "twocan_bxcan::const_plan!: the filters cannot be planned",
        }
    }
}

const fn filter_error_name(e: FilterError) -> &'static str {
    match e {
        FilterError::IdOutOfRange => "the identifier is wider than its format",
        FilterError::MaskOutOfRange => "the mask is wider than the format",
        FilterError::AcceptanceOutsideMask => "the acceptance value has bits outside the mask",
        FilterError::AnyFormatWithIdentifier => "Format::Any with a non-zero mask",
    }
}

impl PlanError {
    /// Panics with a message naming the error and its counts: in `const` code (as in
    /// [`crate::const_plan!`]) a compile-time error that says why the list cannot be
    /// planned.
    pub const fn panic(self) -> ! {
        let m = Message::new().text("twocan_bxcan::const_plan!: ");
        let m = match self {
            PlanError::Filter { index, error } => m
                .text("filter ")
                .number(index as u32)
                .text(" does not conform: ")
                .text(filter_error_name(error)),
            PlanError::TooManyFilters { given, max } => m
                .number(given as u32)
                .text(" filters given, the planner takes at most ")
                .number(max as u32),
            PlanError::TooManyBanks { needed, available } => m
                .text("the filters need ")
                .number(needed as u32)
                .text(" banks, ")
                .number(available as u32)
                .text(" are available"),
            PlanError::DualTooManyBanks {
                can1_needed,
                can2_needed,
                available,
            } => m
                .text("CAN1's filters need ")
                .number(can1_needed as u32)
                .text(" banks and CAN2's ")
                .number(can2_needed as u32)
                .text(", the block has ")
                .number(available as u32),
            PlanError::TooManyLookupKeys { needed, max } => m
                .text("the plan needs ")
                .number(needed as u32)
                .text(" lookup keys, the capacity is ")
                .number(max as u32),
            PlanError::TooManyMatchIndices { needed, max } => m
                .text("the plan numbers ")
                .number(needed as u32)
                .text(" match indices in a FIFO, the map holds ")
                .number(max as u32),
            PlanError::BankOutOfRange => m.text("a bank index above 27"),
        };
        panic!("{}", m.as_str())
    }
}

impl From<PlanError> for twocan_core::Error {
    /// Keeps the counts: [`twocan_core::Error::FilterSpace`] with banks needed and
    /// available (both instances' needs added for a dual plan), or filters given and the
    /// most the planner takes.
    fn from(e: PlanError) -> Self {
        match e {
            PlanError::Filter { error, .. } => twocan_core::Error::Filter(error),
            PlanError::TooManyFilters { given, max } => twocan_core::Error::FilterSpace {
                needed: given,
                available: max,
            },
            PlanError::TooManyBanks { needed, available } => twocan_core::Error::FilterSpace {
                needed,
                available: available as u16,
            },
            PlanError::DualTooManyBanks {
                can1_needed,
                can2_needed,
                available,
            } => twocan_core::Error::FilterSpace {
                needed: can1_needed.saturating_add(can2_needed),
                available: available as u16,
            },
            PlanError::TooManyLookupKeys { needed, max }
            | PlanError::TooManyMatchIndices { needed, max } => twocan_core::Error::FilterSpace {
                needed,
                available: max,
            },
            PlanError::BankOutOfRange => twocan_core::Error::InvalidArgument,
        }
    }
}

/// Value of [`FilterPlan::user_index`] slots that map to no user filter.
pub const NO_FILTER: u16 = u16::MAX;

/// Value of [`FilterPlan::user_index`] / [`FmiMap::get`] for a slot whose user index
/// depends on the frame (a mask entry standing for several user filters, or a superset
/// entry): use [`FmiMap::resolve`].
pub const LOOKUP: u16 = u16::MAX - 1;

/// The largest number of filter numbers one FIFO can have (28 banks × 4).
pub const MAX_FMI: usize = FILTER_BANKS * 4;

/// How many identifiers a driver's [`FmiMap`] holds by default for the thread-side
/// lookup ([`FmiMap::resolve`]): the keys (identifier, format, kind) that reach a mask
/// slot standing for several user filters, or a superset slot. Slots of one user filter
/// (list entries, masks of one filter) need no key.
///
/// The map lives in the driver's state (6 bytes a key), so the default is sized for
/// firmware with a modest filter list, not for the planner's
/// [`crate::planner::MAX_FILTERS`]. The planner plans within the capacity of the plan
/// type it fills ([`FilterPlan<K>`]: `K` lookup keys, this by default): a merged plan
/// that would need more keys gives way to one that needs fewer (blocks split back into
/// list entries), or the list is refused at planning time with both counts
/// ([`PlanError::TooManyLookupKeys`]). Of the project's DBC corpus (`bench/data/`), the
/// largest exact plan needs 122 keys and the superset plans of the largest sets up to
/// 365: give such a controller room with [`crate::Init::with_lookup_capacity`] (e.g. 512)
/// and plan with the same `K` ([`crate::planner::plan_for`]). A `const` plan
/// ([`crate::const_plan!`]) carries exactly the keys it needs.
pub const LOOKUP_KEYS: usize = 64;

/// The most lookup keys any plan needs (every key of the largest list): the capacity a
/// `const` plan is computed with before it is cut to its size ([`SizedPlan`]).
pub const MAX_LOOKUP_KEYS: usize = twocan_core::filter_set::MAX_KEYS;

/// What the hardware does with a frame under a plan (see [`FilterPlan::evaluate`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Acceptance {
    /// The FIFO the frame is stored in.
    pub fifo: Fifo,
    /// The filter match index stored with it (`CAN_RDTxR.FMI`).
    pub fmi: u8,
    /// The user's filter index it maps to ([`FmiMap::resolve`]; [`NO_FILTER`] if none:
    /// a frame accepted by a superset plan only, which the driver drops).
    pub filter: u16,
}

/// A bank with every field zero (a deactivated 32-bit mask bank): the content of a
/// fresh planner scratch, so that a `static` of it takes no flash.
const ZERO_BANK: Bank = Bank {
    kind: BankKind::Mask32,
    fifo: Fifo::Fifo0,
    active: false,
    fr1: 0,
    fr2: 0,
};

/// A compiled filter list as the driver and the queries read it, whatever holds it: a
/// run-time [`FilterPlan`] or a `const` [`SizedPlan`] (their `as_ref`). The banks
/// (relative to the instance's first bank), the user index of every bank slot, and the
/// keys (identifier, format, kind) that reach a slot standing for several user filters,
/// with their user indices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlanRef<'a> {
    banks: &'a [Bank],
    users: &'a [[u16; 4]],
    keys: &'a [Key],
    key_users: &'a [u16],
    optimal: bool,
    extra: u64,
    list_only_banks: u16,
}

impl<'a> PlanRef<'a> {
    /// The banks in use (relative to the instance's first bank).
    pub const fn banks(&self) -> &'a [Bank] {
        self.banks
    }

    /// Number of banks in use.
    pub const fn bank_count(&self) -> usize {
        self.banks.len()
    }

    /// The user index of every slot of every bank ([`NO_FILTER`] beyond the bank's
    /// slots).
    pub const fn slot_users(&self) -> &'a [[u16; 4]] {
        self.users
    }

    /// The keys that reach a slot standing for several user filters (ascending), and
    /// their user indices (see [`FilterPlan::key_table`]).
    pub const fn lookup_keys(&self) -> (&'a [Key], &'a [u16]) {
        (self.keys, self.key_users)
    }

    /// See [`FilterPlan::is_proven_optimal`].
    pub const fn is_proven_optimal(&self) -> bool {
        self.optimal
    }

    /// See [`FilterPlan::superset_extra`].
    pub const fn superset_extra(&self) -> u64 {
        self.extra
    }

    /// See [`FilterPlan::list_only_banks`].
    pub const fn list_only_banks(&self) -> u16 {
        self.list_only_banks
    }

    /// The user index of key `k` in the lookup keys.
    pub const fn lookup(&self, k: Key) -> Option<u16> {
        let at = lower_bound(self.keys, k);
        if at < self.keys.len() && self.keys[at] == k {
            Some(self.key_users[at])
        } else {
            None
        }
    }

    /// See [`FilterPlan::slot_user`].
    pub const fn slot_user(&self, bank: usize, slot: usize) -> u16 {
        if bank < self.banks.len() && slot < 4 {
            self.users[bank][slot]
        } else {
            NO_FILTER
        }
    }

    /// See [`FilterPlan::fmi_of`].
    pub const fn fmi_of(&self, bank: usize, slot: usize) -> Option<(Fifo, u8)> {
        if bank >= self.banks.len() {
            return None;
        }
        let b = self.banks[bank];
        if slot >= b.kind.slots() {
            return None;
        }
        let mut before = 0;
        let mut i = 0;
        while i < bank {
            if self.banks[i].fifo as u8 == b.fifo as u8 {
                before += self.banks[i].kind.slots();
            }
            i += 1;
        }
        Some((b.fifo, (before + slot) as u8))
    }

    /// See [`FilterPlan::user_index`].
    pub const fn user_index(&self, fifo: Fifo, fmi: u8) -> u16 {
        let mut next = 0usize;
        let mut b = 0;
        while b < self.banks.len() {
            let bank = self.banks[b];
            if bank.fifo as u8 == fifo as u8 {
                let slots = bank.kind.slots();
                if (fmi as usize) < next + slots {
                    return self.users[b][fmi as usize - next];
                }
                next += slots;
            }
            b += 1;
        }
        NO_FILTER
    }

    /// See [`FilterPlan::resolve`].
    pub const fn resolve(
        &self,
        fifo: Fifo,
        fmi: u8,
        raw_id: u32,
        extended: bool,
        remote: bool,
    ) -> Option<u16> {
        match self.user_index(fifo, fmi) {
            NO_FILTER => None,
            LOOKUP => self.lookup(key(raw_id, extended, remote)),
            user => Some(user),
        }
    }

    /// See [`FilterPlan::uses_fifo`].
    pub const fn uses_fifo(&self, fifo: Fifo) -> bool {
        let mut i = 0;
        while i < self.banks.len() {
            if self.banks[i].active && self.banks[i].fifo as u8 == fifo as u8 {
                return true;
            }
            i += 1;
        }
        false
    }

    /// The hardware's decision for `(id, ext, rtr)` before the key lookup: FIFO, match
    /// index and the slot's user entry (a user index, [`LOOKUP`] or [`NO_FILTER`]); see
    /// [`FilterPlan::evaluate`] for the rules.
    pub const fn decide(&self, id: u32, ext: bool, rtr: bool) -> Option<(Fifo, u8, u16)> {
        // (class, bank, slot): the winner so far.
        let mut best: Option<(u8, usize, usize)> = None;
        let mut i = 0;
        while i < self.banks.len() {
            let b = self.banks[i];
            let mut slot = 0;
            while b.active && slot < b.kind.slots() {
                if b.slot_matches(slot, id, ext, rtr) {
                    let class = b.kind.priority_class();
                    let better = match best {
                        None => true,
                        // Banks and slots are visited in ascending order: only a
                        // better class wins.
                        Some((c, _, _)) => class < c,
                    };
                    if better {
                        best = Some((class, i, slot));
                    }
                }
                slot += 1;
            }
            i += 1;
        }
        match best {
            None => None,
            Some((_, bank, slot)) => match self.fmi_of(bank, slot) {
                Some((fifo, fmi)) => Some((fifo, fmi, self.users[bank][slot])),
                None => None,
            },
        }
    }

    /// See [`FilterPlan::evaluate`].
    pub const fn evaluate(&self, frame: &Frame) -> Option<Acceptance> {
        let (id, ext, rtr) = (frame.raw_id(), frame.is_extended(), frame.is_remote());
        match self.decide(id, ext, rtr) {
            None => None,
            Some((fifo, fmi, user)) => Some(Acceptance {
                fifo,
                fmi,
                filter: match user {
                    LOOKUP => match self.lookup(key(id, ext, rtr)) {
                        Some(u) => u,
                        None => NO_FILTER,
                    },
                    user => user,
                },
            }),
        }
    }

    /// The lookup keys it needs, its banks: what [`SizedPlan`] holds.
    pub const fn sizes(&self) -> PlanSizes {
        PlanSizes {
            banks: self.banks.len(),
            keys: self.keys.len(),
        }
    }

    /// See [`FilterPlan::fmi_map`].
    pub const fn fmi_map<const K: usize>(&self) -> Result<FmiMap<K>, PlanError> {
        self.fmi_map_sized::<K, MAX_FMI>()
    }

    /// [`PlanRef::fmi_map`] with room for `M` match indices per FIFO
    /// ([`PlanRef::match_indices`] at least).
    pub const fn fmi_map_sized<const K: usize, const M: usize>(
        &self,
    ) -> Result<FmiMap<K, M>, PlanError> {
        let mut map = FmiMap::<K, M>::empty();
        match map.fill(*self) {
            Ok(()) => Ok(map),
            Err(e) => Err(e),
        }
    }

    /// The match indices the plan numbers in its busier FIFO: each bank gives as many
    /// as it has slots, active or not (RM0410 §40.7.4 "Filter match index"). The
    /// smallest `M` of a driver map ([`FmiMap`]) that holds the plan: a `const` plan
    /// sizes its controller's map with it (`BxCan<R, F, K, { PLAN.match_indices() }>`).
    pub const fn match_indices(&self) -> usize {
        let mut next = [0usize; 2];
        let mut b = 0;
        while b < self.banks.len() {
            next[self.banks[b].fifo.index()] += self.banks[b].kind.slots();
            b += 1;
        }
        if next[0] > next[1] {
            next[0]
        } else {
            next[1]
        }
    }
}

/// The banks of one instance's share of the filter block, relative to its first bank,
/// with the user index of every slot and room for `K` lookup keys: the compiled filter
/// list that [`twocan_core::Hardware::install_filters`] writes (the driver's `K`, its
/// merged-filter lookup capacity, [`LOOKUP_KEYS`] by default).
///
/// Bank `k` of a plan is written to hardware bank `first + k`, where `first` is 0 for
/// CAN1 and CAN3 and `CAN2SB` for CAN2. Match indices are numbered from the instance's
/// first bank (see `docs/filters.md` on CAN2).
///
/// Built by the planner ([`crate::planner::plan`] in `const` code or on the host,
/// [`crate::planner::plan_in`] at run time with the working memory in a `static`), by
/// [`FilterPlan::manual`] and [`FilterPlan::set_bank`], or from a `const` plan
/// ([`FilterPlan::from_ref`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FilterPlan<const K: usize = LOOKUP_KEYS> {
    banks: [Bank; FILTER_BANKS],
    users: [[u16; 4]; FILTER_BANKS],
    len: u8,
    optimal: bool,
    keys: KeyTable<K>,
    extra: u64,
    list_only_banks: u16,
}

impl<const K: usize> Default for FilterPlan<K> {
    fn default() -> Self {
        Self::empty()
    }
}

impl FilterPlan {
    /// An empty plan: no bank, nothing is received. Add banks with
    /// [`FilterPlan::set_bank`] for direct configuration. (For a controller with
    /// another lookup capacity, `FilterPlan::<K>::empty()`.)
    pub const fn manual() -> Self {
        Self::empty()
    }

    /// The user index a manual plan reports for `slot` of bank `index` (`4 × index +
    /// slot`).
    pub const fn slot_index(index: usize, slot: usize) -> u16 {
        (4 * index + slot) as u16
    }
}

impl<'a, const K: usize> From<&'a FilterPlan<K>> for PlanRef<'a> {
    fn from(p: &'a FilterPlan<K>) -> Self {
        p.as_ref()
    }
}

impl<'a, const K: usize> From<&'a mut FilterPlan<K>> for PlanRef<'a> {
    fn from(p: &'a mut FilterPlan<K>) -> Self {
        p.as_ref()
    }
}

impl<const K: usize> FilterPlan<K> {
    /// An empty plan with room for `K` lookup keys: no bank, nothing is received
    /// ([`FilterPlan::manual`] for the default capacity).
    pub const fn empty() -> Self {
        FilterPlan {
            banks: [Bank::unused(); FILTER_BANKS],
            users: [[NO_FILTER; 4]; FILTER_BANKS],
            len: 0,
            optimal: true,
            keys: KeyTable::new(),
            extra: 0,
            list_only_banks: 0,
        }
    }

    /// All zeros (no bank): a planner scratch's output before its first plan.
    pub(crate) const fn zeroed() -> Self {
        FilterPlan {
            banks: [ZERO_BANK; FILTER_BANKS],
            users: [[0; 4]; FILTER_BANKS],
            len: 0,
            optimal: false,
            keys: KeyTable::new(),
            extra: 0,
            list_only_banks: 0,
        }
    }

    /// Back to [`FilterPlan::manual`], in place.
    pub(crate) const fn reset(&mut self) {
        let mut i = 0;
        while i < FILTER_BANKS {
            self.banks[i] = Bank::unused();
            self.users[i] = [NO_FILTER; 4];
            i += 1;
        }
        self.len = 0;
        self.optimal = true;
        self.keys.clear();
        self.extra = 0;
        self.list_only_banks = 0;
    }

    /// The plan as the driver reads it (borrowed: no copy).
    pub const fn as_ref(&self) -> PlanRef<'_> {
        PlanRef {
            banks: self.banks.split_at(self.len as usize).0,
            users: self.users.split_at(self.len as usize).0,
            keys: self.keys.keys(),
            key_users: self.keys.users(),
            optimal: self.optimal,
            extra: self.extra,
            list_only_banks: self.list_only_banks,
        }
    }

    /// A plan with the content of `plan` (e.g. a `const` [`SizedPlan`]'s, for the split
    /// driver's `set_filters`), in place.
    ///
    /// Errors: [`PlanError::TooManyLookupKeys`] when `plan` needs more lookup keys than
    /// `K`; [`PlanError::BankOutOfRange`] with more than 28 banks.
    pub const fn copy_from(&mut self, plan: PlanRef<'_>) -> Result<(), PlanError> {
        if plan.banks.len() > FILTER_BANKS || plan.users.len() != plan.banks.len() {
            return Err(PlanError::BankOutOfRange);
        }
        if plan.keys.len() > K {
            return Err(PlanError::TooManyLookupKeys {
                needed: plan.keys.len() as u16,
                max: K as u16,
            });
        }
        self.reset();
        let mut i = 0;
        while i < plan.banks.len() {
            self.banks[i] = plan.banks[i];
            self.users[i] = plan.users[i];
            i += 1;
        }
        self.len = plan.banks.len() as u8;
        if self.keys.copy_from(plan.keys, plan.key_users).is_err() {
            return Err(PlanError::BankOutOfRange);
        }
        self.optimal = plan.optimal;
        self.extra = plan.extra;
        self.list_only_banks = plan.list_only_banks;
        Ok(())
    }

    /// A plan with the content of `plan` (see [`FilterPlan::copy_from`]); by value, so
    /// about 1 KB moves: prefer passing `plan` itself where a [`PlanRef`] is taken
    /// ([`crate::Init::set_filters`]).
    pub const fn from_ref(plan: PlanRef<'_>) -> Result<Self, PlanError> {
        let mut p = Self::empty();
        match p.copy_from(plan) {
            Ok(()) => Ok(p),
            Err(e) => Err(e),
        }
    }

    /// Sets bank `index` (relative to the instance's first bank). Its slots report user
    /// indices `4 × index + slot`, so that every slot of a manual plan has its own index
    /// (use [`FilterPlan::slot_index`]). Banks below `index` not set yet stay
    /// [`Bank::unused`] (they count in the numbering as deactivated 16-bit mask banks).
    pub const fn set_bank(&mut self, index: usize, bank: Bank) -> Result<(), PlanError> {
        if index >= FILTER_BANKS {
            return Err(PlanError::BankOutOfRange);
        }
        self.banks[index] = bank;
        let mut users = [NO_FILTER; 4];
        let mut slot = 0;
        while slot < bank.kind.slots() {
            users[slot] = (4 * index + slot) as u16;
            slot += 1;
        }
        self.users[index] = users;
        if index >= self.len as usize {
            self.len = index as u8 + 1;
        }
        self.optimal = false;
        Ok(())
    }

    /// Built by the planner (crate-internal).
    pub(crate) const fn push(&mut self, bank: Bank, users: [u16; 4]) -> Result<(), PlanError> {
        let i = self.len as usize;
        if i >= FILTER_BANKS {
            return Err(PlanError::BankOutOfRange);
        }
        self.banks[i] = bank;
        self.users[i] = users;
        self.len += 1;
        Ok(())
    }

    pub(crate) const fn set_fifo(&mut self, index: usize, fifo: Fifo) {
        self.banks[index].fifo = fifo;
    }

    pub(crate) const fn set_optimal(&mut self, optimal: bool) {
        self.optimal = optimal;
    }

    /// Keeps, of the user's keys, those the hardware routes to a slot that stands for
    /// several user filters ([`LOOKUP`]): the only ones [`FmiMap::resolve`] searches.
    /// Call after every bank and its users are in place.
    ///
    /// Errors: [`PlanError::TooManyLookupKeys`] with the keys needed when they are more
    /// than `K` (the plan keeps none).
    pub(crate) const fn set_resolution<const N: usize>(
        &mut self,
        keys: &KeyTable<N>,
        extra: u64,
        list_only_banks: u16,
    ) -> Result<(), PlanError> {
        self.extra = extra;
        self.list_only_banks = list_only_banks;
        self.keys.clear();
        let needed = self.lookup_need(keys);
        if needed > K {
            return Err(PlanError::TooManyLookupKeys {
                needed: needed as u16,
                max: K as u16,
            });
        }
        let k = keys.keys();
        let u = keys.users();
        let mut i = 0;
        while i < k.len() {
            let (id, ext, rtr) = key_parts(k[i]);
            if let Some((_, _, LOOKUP)) = self.as_ref().decide(id, ext, rtr) {
                // Counted above: room for every one.
                let _ = self.keys.insert(k[i], u[i]);
            }
            i += 1;
        }
        Ok(())
    }

    /// How many of `keys` the banks route to a slot standing for several user filters.
    pub(crate) const fn lookup_need<const N: usize>(&self, keys: &KeyTable<N>) -> usize {
        let k = keys.keys();
        let mut needed = 0;
        let mut i = 0;
        while i < k.len() {
            let (id, ext, rtr) = key_parts(k[i]);
            if let Some((_, _, LOOKUP)) = self.as_ref().decide(id, ext, rtr) {
                needed += 1;
            }
            i += 1;
        }
        needed
    }

    /// Identifiers the hardware accepts beyond the user's filters (0 for an exact plan;
    /// counted entry by entry, so an upper bound if superset entries overlap). The
    /// driver drops frames with these identifiers ([`FmiMap::resolve`] gives `None`).
    pub const fn superset_extra(&self) -> u64 {
        self.extra
    }

    /// Whether the hardware accepts more than the user's filters (superset mode).
    pub const fn is_superset(&self) -> bool {
        self.extra != 0
    }

    /// Banks the same list takes without merging (one list or mask entry per user
    /// filter), as the planner computed it; 0 for manual plans.
    pub const fn list_only_banks(&self) -> u16 {
        self.list_only_banks
    }

    /// The keys (identifier, format, kind) that reach a slot standing for several user
    /// filters, with their user indices: the table [`FmiMap::resolve`] searches (empty
    /// for a plan without merged or superset slots; never more than `K`).
    pub const fn key_table(&self) -> &KeyTable<K> {
        &self.keys
    }

    /// The user index of a frame the hardware stored in `fifo` with match index `fmi`
    /// (see [`FmiMap::resolve`]).
    pub const fn resolve(
        &self,
        fifo: Fifo,
        fmi: u8,
        raw_id: u32,
        extended: bool,
        remote: bool,
    ) -> Option<u16> {
        self.as_ref().resolve(fifo, fmi, raw_id, extended, remote)
    }

    /// Of `traffic` (frames with a weight each, e.g. their rate on the bus), the weight
    /// the hardware accepts and the weight the driver then drops (accepted by a superset
    /// entry only): `(accepted, dropped)`. The expected software drop rate is
    /// `dropped / accepted` of received frames, `dropped / total` of bus traffic.
    pub fn drop_weight<'a>(
        &self,
        traffic: impl IntoIterator<Item = (&'a Frame, u64)>,
    ) -> (u64, u64) {
        let mut accepted = 0u64;
        let mut dropped = 0u64;
        for (frame, w) in traffic {
            if let Some(a) = self.evaluate(frame) {
                accepted += w;
                if a.filter == NO_FILTER {
                    dropped += w;
                }
            }
        }
        (accepted, dropped)
    }

    /// The banks in use (relative to the instance's first bank).
    pub const fn banks(&self) -> &[Bank] {
        self.banks.split_at(self.len as usize).0
    }

    /// Number of banks in use.
    pub const fn bank_count(&self) -> usize {
        self.len as usize
    }

    /// Whether the planner proved this plan uses the fewest banks (see
    /// [`crate::planner`]); `false` for manual plans.
    pub const fn is_proven_optimal(&self) -> bool {
        self.optimal
    }

    /// User filter index of slot `slot` of bank `bank` ([`NO_FILTER`] if none).
    pub const fn slot_user(&self, bank: usize, slot: usize) -> u16 {
        self.as_ref().slot_user(bank, slot)
    }

    /// The FIFO and filter match index of slot `slot` of bank `bank` (notes "Filter
    /// match index": per FIFO, in bank order, every bank counting whether active or not).
    pub const fn fmi_of(&self, bank: usize, slot: usize) -> Option<(Fifo, u8)> {
        self.as_ref().fmi_of(bank, slot)
    }

    /// The map from each FIFO's match index to the user's filter index, with room for
    /// `K2` lookup keys (the driver's map: [`LOOKUP_KEYS`] unless the controller was
    /// given another capacity).
    ///
    /// Errors: [`PlanError::TooManyLookupKeys`] when the plan's merged or superset slots
    /// leave more identifiers to the lookup than `K2` ([`FilterPlan::key_table`]).
    pub const fn fmi_map<const K2: usize>(&self) -> Result<FmiMap<K2>, PlanError> {
        self.as_ref().fmi_map::<K2>()
    }

    /// See [`PlanRef::fmi_map_sized`].
    pub const fn fmi_map_sized<const K2: usize, const M2: usize>(
        &self,
    ) -> Result<FmiMap<K2, M2>, PlanError> {
        self.as_ref().fmi_map_sized::<K2, M2>()
    }

    /// See [`PlanRef::match_indices`].
    pub const fn match_indices(&self) -> usize {
        self.as_ref().match_indices()
    }

    /// The user index reported for a frame stored in `fifo` with match index `fmi`
    /// ([`NO_FILTER`] if no slot has it, [`LOOKUP`] if it depends on the identifier).
    pub const fn user_index(&self, fifo: Fifo, fmi: u8) -> u16 {
        self.as_ref().user_index(fifo, fmi)
    }

    /// The hardware's decision for a frame, by the notes' rules: among the active banks'
    /// filters that accept it, a 32-bit filter wins over a 16-bit one, then list over
    /// mask, then the lower filter number. `None`: the frame is discarded.
    ///
    /// The notes and RM0410 do not say how filters of different FIFOs compare (filter
    /// numbers are per FIFO); here, as in the behavioural model, a tie of class goes to
    /// the lower bank number (then the lower position in the bank, which within one FIFO
    /// is the lower filter number). Plans made by the planner never let one frame match
    /// filters of both FIFOs (overlapping filters share a FIFO), so the question only
    /// arises for manual plans; check it on silicon before relying on it.
    ///
    /// [`Acceptance::filter`] is the resolved user index ([`FmiMap::resolve`]):
    /// [`NO_FILTER`] for a frame a superset plan accepts that no user filter does.
    pub const fn evaluate(&self, frame: &Frame) -> Option<Acceptance> {
        self.as_ref().evaluate(frame)
    }

    /// Whether any bank of the plan sends frames to `fifo`.
    pub const fn uses_fifo(&self, fifo: Fifo) -> bool {
        self.as_ref().uses_fifo(fifo)
    }

    /// Its banks and the lookup keys it needs: the sizes of its [`SizedPlan`].
    pub const fn sizes(&self) -> PlanSizes {
        self.as_ref().sizes()
    }

    /// The same plan in a [`SizedPlan`] of exactly its banks and lookup keys (`B` and
    /// `KEYS` from [`FilterPlan::sizes`]; other sizes panic — in `const` code, a
    /// compile-time error). See [`crate::const_plan!`].
    pub const fn sized<const B: usize, const KEYS: usize>(&self) -> SizedPlan<B, KEYS> {
        let s = self.sizes();
        if s.banks != B || s.keys != KEYS {
            panic!("SizedPlan sizes differ from the plan's (use FilterPlan::sizes)");
        }
        let mut out = SizedPlan {
            banks: [ZERO_BANK; B],
            users: [[0; 4]; B],
            keys: [0; KEYS],
            key_users: [0; KEYS],
            optimal: self.optimal,
            extra: self.extra,
            list_only_banks: self.list_only_banks,
        };
        let mut i = 0;
        while i < B {
            out.banks[i] = self.banks[i];
            out.users[i] = self.users[i];
            i += 1;
        }
        let (k, u) = (self.keys.keys(), self.keys.users());
        let mut i = 0;
        while i < KEYS {
            out.keys[i] = k[i];
            out.key_users[i] = u[i];
            i += 1;
        }
        out
    }
}

/// The sizes of a plan: its banks and the lookup keys its merged or superset slots need
/// (the const parameters of its [`SizedPlan`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlanSizes {
    /// Banks in use.
    pub banks: usize,
    /// Lookup keys needed.
    pub keys: usize,
}

/// A plan sized to itself: `B` banks and exactly the `K` lookup keys its merged or
/// superset slots need — what [`crate::const_plan!`] gives for a `const` filter list, a
/// `&'static` value with nothing the installed filters do not use.
///
/// It holds the bank register values ([`Bank`]: `FSCi`, `FBMi`, `FFAi`, `FACTi`,
/// `FiR1`, `FiR2`), the user index of every bank slot (the map from each FIFO's filter
/// match index back to the user's filter, [`SizedPlan::user_index`]) and the lookup
/// keys ([`SizedPlan::resolve`]). [`crate::Init::set_filters`] installs it as it is;
/// the split driver's `set_filters` takes a [`FilterPlan`] ([`FilterPlan::from_ref`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SizedPlan<const B: usize, const K: usize> {
    banks: [Bank; B],
    users: [[u16; 4]; B],
    keys: [Key; K],
    key_users: [u16; K],
    optimal: bool,
    extra: u64,
    list_only_banks: u16,
}

impl<'a, const B: usize, const K: usize> From<&'a SizedPlan<B, K>> for PlanRef<'a> {
    fn from(p: &'a SizedPlan<B, K>) -> Self {
        p.as_ref()
    }
}

impl<const B: usize, const K: usize> SizedPlan<B, K> {
    /// The plan as the driver reads it.
    pub const fn as_ref(&self) -> PlanRef<'_> {
        PlanRef {
            banks: &self.banks,
            users: &self.users,
            keys: &self.keys,
            key_users: &self.key_users,
            optimal: self.optimal,
            extra: self.extra,
            list_only_banks: self.list_only_banks,
        }
    }

    /// The banks (relative to the instance's first bank).
    pub const fn banks(&self) -> &[Bank; B] {
        &self.banks
    }

    /// Number of banks.
    pub const fn bank_count(&self) -> usize {
        B
    }

    /// The lookup keys (ascending) and their user indices.
    pub const fn lookup_keys(&self) -> (&[Key; K], &[u16; K]) {
        (&self.keys, &self.key_users)
    }

    /// See [`FilterPlan::is_proven_optimal`].
    pub const fn is_proven_optimal(&self) -> bool {
        self.optimal
    }

    /// See [`FilterPlan::superset_extra`].
    pub const fn superset_extra(&self) -> u64 {
        self.extra
    }

    /// See [`FilterPlan::list_only_banks`].
    pub const fn list_only_banks(&self) -> u16 {
        self.list_only_banks
    }

    /// See [`FilterPlan::slot_user`].
    pub const fn slot_user(&self, bank: usize, slot: usize) -> u16 {
        self.as_ref().slot_user(bank, slot)
    }

    /// See [`FilterPlan::fmi_of`].
    pub const fn fmi_of(&self, bank: usize, slot: usize) -> Option<(Fifo, u8)> {
        self.as_ref().fmi_of(bank, slot)
    }

    /// See [`FilterPlan::user_index`].
    pub const fn user_index(&self, fifo: Fifo, fmi: u8) -> u16 {
        self.as_ref().user_index(fifo, fmi)
    }

    /// The user's filter index of a frame stored in `fifo` with match index `fmi` (see
    /// [`FmiMap::resolve`]).
    pub const fn resolve(
        &self,
        fifo: Fifo,
        fmi: u8,
        raw_id: u32,
        extended: bool,
        remote: bool,
    ) -> Option<u16> {
        self.as_ref().resolve(fifo, fmi, raw_id, extended, remote)
    }

    /// See [`FilterPlan::evaluate`].
    pub const fn evaluate(&self, frame: &Frame) -> Option<Acceptance> {
        self.as_ref().evaluate(frame)
    }

    /// See [`FilterPlan::uses_fifo`].
    pub const fn uses_fifo(&self, fifo: Fifo) -> bool {
        self.as_ref().uses_fifo(fifo)
    }

    /// See [`FilterPlan::fmi_map`].
    pub const fn fmi_map<const K2: usize>(&self) -> Result<FmiMap<K2>, PlanError> {
        self.as_ref().fmi_map::<K2>()
    }

    /// See [`PlanRef::fmi_map_sized`].
    pub const fn fmi_map_sized<const K2: usize, const M2: usize>(
        &self,
    ) -> Result<FmiMap<K2, M2>, PlanError> {
        self.as_ref().fmi_map_sized::<K2, M2>()
    }

    /// See [`PlanRef::match_indices`].
    pub const fn match_indices(&self) -> usize {
        self.as_ref().match_indices()
    }
}

/// Map from (FIFO, filter match index) to the user's filter index, kept by the
/// controller for [`twocan_core::RxFrame::filter`].
#[derive(Debug, Clone, PartialEq, Eq)]
///
/// `K`: the capacity of its merged-filter lookup (identifiers); `M`: the match indices
/// it holds per FIFO, [`MAX_FMI`] (every bank of the block, four slots each) unless a
/// `const` plan sizes it ([`PlanRef::match_indices`]): 4 bytes per index.
pub struct FmiMap<const K: usize = LOOKUP_KEYS, const M: usize = MAX_FMI> {
    map: [[u16; M]; 2],
    keys: KeyTable<K>,
}

impl<const K: usize, const M: usize> FmiMap<K, M> {
    /// A map where nothing maps ([`NO_FILTER`] everywhere).
    pub const fn empty() -> Self {
        FmiMap {
            map: [[NO_FILTER; M]; 2],
            keys: KeyTable::new(),
        }
    }

    /// Makes this map the map of `plan`, in place (no map value is built and moved:
    /// how the in-place constructors, [`crate::BxCan::can1_in`], fill the controller's
    /// map in its `static`). Each FIFO's match indices are numbered in bank order, each
    /// bank giving as many as it has slots (RM0410 §40.7.4 "Filter match index").
    ///
    /// Errors: [`PlanError::TooManyLookupKeys`] when `plan` needs more lookup keys than
    /// `K`, [`PlanError::TooManyMatchIndices`] when it numbers more match indices in a
    /// FIFO than `M` (the map is then empty: nothing maps).
    pub const fn fill(&mut self, plan: PlanRef<'_>) -> Result<(), PlanError> {
        let mut f = 0;
        while f < 2 {
            let mut i = 0;
            while i < M {
                self.map[f][i] = NO_FILTER;
                i += 1;
            }
            f += 1;
        }
        if plan.match_indices() > M {
            return Err(PlanError::TooManyMatchIndices {
                needed: plan.match_indices() as u16,
                max: M as u16,
            });
        }
        if self.keys.copy_from(plan.keys, plan.key_users).is_err() {
            return Err(PlanError::TooManyLookupKeys {
                needed: plan.keys.len() as u16,
                max: K as u16,
            });
        }
        let mut next = [0usize; 2];
        let mut b = 0;
        while b < plan.banks.len() {
            let f = plan.banks[b].fifo.index();
            let mut s = 0;
            while s < plan.banks[b].kind.slots() {
                if next[f] < M {
                    self.map[f][next[f]] = plan.users[b][s];
                }
                next[f] += 1;
                s += 1;
            }
            b += 1;
        }
        Ok(())
    }

    /// Writes an empty map ([`FmiMap::empty`]) at `map`, in place.
    ///
    /// # Safety
    /// `map` is valid for writes and aligned (it may be uninitialised).
    #[allow(unsafe_code)]
    pub(crate) unsafe fn write_empty(map: *mut Self) {
        // SAFETY: the caller's contract. `NO_FILTER` is `u16::MAX`, every byte 0xFF;
        // an empty key table is all zeros (`KeyTable::new`), valid for its integer
        // fields.
        unsafe {
            core::ptr::addr_of_mut!((*map).map).write_bytes(0xFF, 1);
            core::ptr::addr_of_mut!((*map).keys).write_bytes(0, 1);
        }
    }

    /// The thread-side resolver: the user's filter index of a frame the hardware stored
    /// in `fifo` with match index `fmi` (`CAN_RDTxR.FMI`), given the frame's raw
    /// identifier, format and kind (`CAN_RIxR`).
    ///
    /// - a slot of one user filter: that index (a table lookup);
    /// - a mask slot standing for several user filters (merged identifiers) or for a
    ///   superset: the user filter of the frame's identifier, by binary search in the
    ///   plan's key table (at most ⌈log₂ K⌉ steps); `None` for an identifier no user
    ///   filter accepts — a frame the hardware took only because of a superset plan,
    ///   which the driver drops and counts;
    /// - an FMI no slot has (not produced by the hardware for this plan): `None`.
    pub fn resolve(
        &self,
        fifo: Fifo,
        fmi: u8,
        raw_id: u32,
        extended: bool,
        remote: bool,
    ) -> Option<u16> {
        match self.get(fifo, fmi) {
            NO_FILTER => None,
            LOOKUP => self.keys.lookup(key(raw_id, extended, remote)),
            user => Some(user),
        }
    }

    /// The user index for `fmi` in `fifo`, [`NO_FILTER`] if none, [`LOOKUP`] if it
    /// depends on the frame ([`FmiMap::resolve`]).
    pub fn get(&self, fifo: Fifo, fmi: u8) -> u16 {
        self.map[fifo.index()]
            .get(fmi as usize)
            .copied()
            .unwrap_or(NO_FILTER)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_follow_the_register_layout() {
        // Standard 0x123 data: STID at 31:21.
        assert_eq!(frame_word32(0x123, false, false), 0x123 << 21);
        assert_eq!(
            frame_word32(0x1234_5678, true, true),
            (0x1234_5678 << 3) | 0b110
        );
        assert_eq!(frame_word16(0x7FF, false, true), 0xFFF0);
        // Extended: STID part = id >> 18, EXID[17:15] in bits 2:0, IDE bit 3.
        assert_eq!(frame_word16(0x1FFF_8000, true, false), 0xFFEF);
    }
}
