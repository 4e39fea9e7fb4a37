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

use twocan_core::filter_set::{key, key_parts, KeyTable, MAX_KEYS};
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
    /// lookup than the driver keeps ([`LOOKUP_KEYS`]).
    TooManyLookupKeys {
        /// Identifiers that would need the lookup.
        needed: u16,
        /// [`LOOKUP_KEYS`].
        max: u16,
    },
    /// A bank index beyond the filter block (0..28).
    BankOutOfRange,
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
            PlanError::TooManyLookupKeys { needed, max } => twocan_core::Error::FilterSpace {
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
/// [`crate::planner::MAX_FILTERS`]. Of the project's DBC corpus (`bench/data/`), the
/// largest exact plan needs 122 keys and the superset plans of the largest sets up to 365:
/// give such a controller room with [`crate::Init::with_lookup_capacity`] (e.g. 512).
/// A plan that needs more than the map holds is refused when installed
/// ([`PlanError::TooManyLookupKeys`], [`twocan_core::Error::FilterSpace`] with both
/// counts); [`FilterPlan::key_table`] tells how many it needs.
pub const LOOKUP_KEYS: usize = 64;

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

/// The banks of one instance's share of the filter block, relative to its first bank,
/// with the user index of every slot: the compiled filter list that
/// [`twocan_core::Hardware::install_filters`] writes.
///
/// Bank `k` of a plan is written to hardware bank `first + k`, where `first` is 0 for
/// CAN1 and CAN3 and `CAN2SB` for CAN2. Match indices are numbered from the instance's
/// first bank (see `docs/filters.md` on CAN2).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FilterPlan {
    banks: [Bank; FILTER_BANKS],
    users: [[u16; 4]; FILTER_BANKS],
    len: u8,
    optimal: bool,
    keys: KeyTable,
    extra: u64,
    list_only_banks: u16,
}

impl Default for FilterPlan {
    fn default() -> Self {
        Self::manual()
    }
}

impl FilterPlan {
    /// An empty plan: no bank, nothing is received. Add banks with
    /// [`FilterPlan::set_bank`] for direct configuration.
    pub const fn manual() -> Self {
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

    /// Sets bank `index` (relative to the instance's first bank). Its slots report user
    /// indices `4 × index + slot`, so that every slot of a manual plan has its own index
    /// (use [`FilterPlan::slot_index`]). Banks below `index` not set yet stay
    /// [`Bank::unused`] (they count in the numbering as deactivated 16-bit mask banks).
    pub fn set_bank(&mut self, index: usize, bank: Bank) -> Result<(), PlanError> {
        if index >= FILTER_BANKS {
            return Err(PlanError::BankOutOfRange);
        }
        self.banks[index] = bank;
        let mut users = [NO_FILTER; 4];
        for (slot, u) in users.iter_mut().enumerate().take(bank.kind.slots()) {
            *u = (4 * index + slot) as u16;
        }
        self.users[index] = users;
        if index >= self.len as usize {
            self.len = index as u8 + 1;
        }
        self.optimal = false;
        Ok(())
    }

    /// The user index a manual plan reports for `slot` of bank `index` (`4 × index +
    /// slot`).
    pub const fn slot_index(index: usize, slot: usize) -> u16 {
        (4 * index + slot) as u16
    }

    /// Built by the planner (crate-internal).
    pub(crate) fn push(&mut self, bank: Bank, users: [u16; 4]) -> Result<(), PlanError> {
        let i = self.len as usize;
        if i >= FILTER_BANKS {
            return Err(PlanError::BankOutOfRange);
        }
        self.banks[i] = bank;
        self.users[i] = users;
        self.len += 1;
        Ok(())
    }

    pub(crate) fn set_fifo(&mut self, index: usize, fifo: Fifo) {
        self.banks[index].fifo = fifo;
    }

    pub(crate) fn set_optimal(&mut self, optimal: bool) {
        self.optimal = optimal;
    }

    /// Keeps, of the user's keys, those the hardware routes to a slot that stands for
    /// several user filters ([`LOOKUP`]): the only ones [`FmiMap::resolve`] searches.
    /// Call after every bank and its users are in place.
    pub(crate) fn set_resolution(
        &mut self,
        keys: &KeyTable,
        extra: u64,
        list_only_banks: u16,
    ) -> Result<(), PlanError> {
        let mut lookup = KeyTable::new();
        for (&k, &user) in keys.keys().iter().zip(keys.users()) {
            let (id, ext, rtr) = key_parts(k);
            if let Some((_, _, LOOKUP)) = self.decide(id, ext, rtr) {
                // A subset of `keys`, which has the same capacity: it fits.
                lookup
                    .insert(k, user)
                    .map_err(|_| PlanError::TooManyLookupKeys {
                        needed: keys.len() as u16,
                        max: MAX_KEYS as u16,
                    })?;
            }
        }
        self.keys = lookup;
        self.extra = extra;
        self.list_only_banks = list_only_banks;
        Ok(())
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
    /// for a plan without merged or superset slots).
    pub fn key_table(&self) -> &KeyTable {
        &self.keys
    }

    /// The user index of a frame the hardware stored in `fifo` with match index `fmi`
    /// (see [`FmiMap::resolve`]).
    pub fn resolve(
        &self,
        fifo: Fifo,
        fmi: u8,
        raw_id: u32,
        extended: bool,
        remote: bool,
    ) -> Option<u16> {
        match self.user_index(fifo, fmi) {
            NO_FILTER => None,
            LOOKUP => self.keys.lookup(key(raw_id, extended, remote)),
            user => Some(user),
        }
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
    pub fn banks(&self) -> &[Bank] {
        &self.banks[..self.len as usize]
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
    pub fn slot_user(&self, bank: usize, slot: usize) -> u16 {
        if bank < self.len as usize && slot < 4 {
            self.users[bank][slot]
        } else {
            NO_FILTER
        }
    }

    /// The FIFO and filter match index of slot `slot` of bank `bank` (notes "Filter
    /// match index": per FIFO, in bank order, every bank counting whether active or not).
    pub fn fmi_of(&self, bank: usize, slot: usize) -> Option<(Fifo, u8)> {
        let b = self.banks().get(bank)?;
        if slot >= b.kind.slots() {
            return None;
        }
        let before: usize = self.banks[..bank]
            .iter()
            .filter(|x| x.fifo == b.fifo)
            .map(|x| x.kind.slots())
            .sum();
        Some((b.fifo, (before + slot) as u8))
    }

    /// The map from each FIFO's match index to the user's filter index, with room for
    /// `K` lookup keys (the driver's map: [`LOOKUP_KEYS`] unless the controller was
    /// given another capacity).
    ///
    /// Errors: [`PlanError::TooManyLookupKeys`] when the plan's merged or superset slots
    /// leave more identifiers to the lookup than `K` ([`FilterPlan::key_table`]).
    pub fn fmi_map<const K: usize>(&self) -> Result<FmiMap<K>, PlanError> {
        let mut map = FmiMap::<K>::empty();
        for (&k, &user) in self.keys.keys().iter().zip(self.keys.users()) {
            map.keys
                .insert(k, user)
                .map_err(|_| PlanError::TooManyLookupKeys {
                    needed: self.keys.len() as u16,
                    max: K as u16,
                })?;
        }
        let mut next = [0usize; 2];
        for (b, users) in self.banks().iter().zip(self.users.iter()) {
            let f = b.fifo.index();
            for &u in users.iter().take(b.kind.slots()) {
                if next[f] < MAX_FMI {
                    map.map[f][next[f]] = u;
                }
                next[f] += 1;
            }
        }
        Ok(map)
    }

    /// The user index reported for a frame stored in `fifo` with match index `fmi`
    /// ([`NO_FILTER`] if no slot has it, [`LOOKUP`] if it depends on the identifier).
    pub fn user_index(&self, fifo: Fifo, fmi: u8) -> u16 {
        let mut next = 0usize;
        for (b, users) in self.banks().iter().zip(self.users.iter()) {
            if b.fifo != fifo {
                continue;
            }
            for &u in users.iter().take(b.kind.slots()) {
                if next == fmi as usize {
                    return u;
                }
                next += 1;
            }
        }
        NO_FILTER
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
    pub fn evaluate(&self, frame: &Frame) -> Option<Acceptance> {
        let (id, ext, rtr) = (frame.raw_id(), frame.is_extended(), frame.is_remote());
        self.decide(id, ext, rtr)
            .map(|(fifo, fmi, user)| Acceptance {
                fifo,
                fmi,
                filter: match user {
                    LOOKUP => self.keys.lookup(key(id, ext, rtr)).unwrap_or(NO_FILTER),
                    user => user,
                },
            })
    }

    /// [`FilterPlan::evaluate`] before the key lookup: FIFO, match index and the slot's
    /// user entry (a user index, [`LOOKUP`] or [`NO_FILTER`]).
    fn decide(&self, id: u32, ext: bool, rtr: bool) -> Option<(Fifo, u8, u16)> {
        // (class, bank, slot, FIFO, FMI, user index)
        let mut best: Option<(u8, usize, usize, Fifo, u8, u16)> = None;
        for (i, b) in self.banks().iter().enumerate() {
            if !b.active {
                continue;
            }
            for slot in 0..b.kind.slots() {
                if !b.slot_matches(slot, id, ext, rtr) {
                    continue;
                }
                let Some((fifo, fmi)) = self.fmi_of(i, slot) else {
                    continue;
                };
                let key = (
                    b.kind.priority_class(),
                    i,
                    slot,
                    fifo,
                    fmi,
                    self.users[i][slot],
                );
                let better = match best {
                    None => true,
                    Some(bk) => (key.0, key.1, key.2) < (bk.0, bk.1, bk.2),
                };
                if better {
                    best = Some(key);
                }
            }
        }
        best.map(|(_, _, _, fifo, fmi, user)| (fifo, fmi, user))
    }

    /// Whether any bank of the plan sends frames to `fifo`.
    pub fn uses_fifo(&self, fifo: Fifo) -> bool {
        self.banks().iter().any(|b| b.active && b.fifo == fifo)
    }
}

/// Map from (FIFO, filter match index) to the user's filter index, kept by the
/// controller for [`twocan_core::RxFrame::filter`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FmiMap<const K: usize = LOOKUP_KEYS> {
    map: [[u16; MAX_FMI]; 2],
    keys: KeyTable<K>,
}

impl<const K: usize> FmiMap<K> {
    /// A map where nothing maps ([`NO_FILTER`] everywhere).
    pub const fn empty() -> Self {
        FmiMap {
            map: [[NO_FILTER; MAX_FMI]; 2],
            keys: KeyTable::new(),
        }
    }

    /// The thread-side resolver: the user's filter index of a frame the hardware stored
    /// in `fifo` with match index `fmi` (`CAN_RDTxR.FMI`), given the frame's raw
    /// identifier, format and kind (`CAN_RIxR`).
    ///
    /// - a slot of one user filter: that index (a table lookup);
    /// - a mask slot standing for several user filters (merged identifiers) or for a
    ///   superset: the user filter of the frame's identifier, by binary search in the
    ///   plan's key table (at most ⌈log₂ 256⌉ = 8 steps); `None` for an identifier no
    ///   user filter accepts — a frame the hardware took only because of a superset
    ///   plan, which the driver drops and counts;
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
