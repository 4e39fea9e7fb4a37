//! The in-place and planned forms of a token's `begin` (issue 21), for every board's
//! tokens (`Can0`/`Can1` of the Teensy 3.x, `Can1`–`Can3` of the Teensy 4.x): the
//! token-level counterparts of [`crate::FlexCan::begin_in`] and
//! [`crate::FlexCan::begin_checked`]. They give the split controller straight away,
//! whose table is a reference (to a [`crate::filters::TableSlot`] or to a plan made at
//! compile time), so that no table-sized value moves through a firmware's
//! configuration. The board difference (the chip-level registers) is the `$system`
//! function each firmware module passes. The in-place forms and `end_split` take the
//! state's register type: the run-time window or the module's fixed base
//! ([`crate::TokenRegisters`], made from the token's window by one check,
//! `Mmio::into_fixed`).

/// Defines `begin_in` and `begin_planned` on `$token`, whose chip-level registers
/// `$system()` gives.
macro_rules! token_begin {
    ($token:ident, $system:ident) => {
        impl $token {
            /// `begin` compiling the lists straight into `slot`, a table in a `static`
            /// ([`crate::filters::TableSlot`]), and giving the split controller with the
            /// options `O` ([`crate::options::FullInSlot`]): every feature of `begin` +
            /// `into_split`, no table-sized value on the stack
            /// ([`crate::FlexCan::begin_in`]). On error the token and the slot come back
            /// with the reason.
            #[allow(clippy::type_complexity)]
            pub fn begin_in<O, L>(
                self,
                settings: &$crate::Settings,
                primary: &[twocan_core::Filter],
                secondary: &[twocan_core::Filter],
                slot: &'static mut L::Table,
            ) -> Result<
                $crate::FlexCanHw<$crate::regs::FlexCanRegs, O>,
                (Self, $crate::BeginError, &'static mut L::Table),
            >
            where
                L: $crate::layout::Layout,
                O: $crate::options::Options<Layout = L, Table = &'static mut L::Table>,
            {
                let target = self.target();
                let Some(base) = target.base() else {
                    return Err((
                        self,
                        $crate::BeginError::Config($crate::ConfigErrors::NO_SUCH_INSTANCE),
                        slot,
                    ));
                };
                // SAFETY: the token is unique (taken once) and consumed here (given back
                // only with an error, after this handle is gone), so this is the only
                // access to the module, at its reference-manual base address.
                let regs = unsafe { $crate::regs::FlexCanRegs::new(base) };
                $crate::FlexCan::begin_in(
                    regs,
                    &mut $system(),
                    target,
                    settings,
                    primary,
                    secondary,
                    slot,
                )
                .map_err(|(e, slot)| (self, e, slot))
            }

            /// The module's registers for a begin with `checked`, as the handle `R`
            /// ([`crate::TokenRegisters`]: the run-time window, or the module's fixed
            /// base checked by `Mmio::into_fixed`): `None` when the plan was made for
            /// another module (or the board has no such module), or `R`'s base is not
            /// the module's.
            fn checked_regs<L: $crate::layout::Layout, R: $crate::TokenRegisters<Self>>(
                &self,
                checked: &$crate::BeginPlan<L>,
            ) -> Option<R> {
                let target = self.target();
                let base = target.base().filter(|_| checked.target() == target)?;
                // SAFETY: as for `begin_in`: the token is unique and the caller consumes
                // it (giving it back only with an error, after the handle is gone).
                let window = unsafe { $crate::regs::FlexCanRegs::new(base) };
                R::from_window(window).ok()
            }

            /// [`Self::begin_in`] writing the split controller **in place** into `hw`,
            /// the storage a `static` state lends (`rt::IrqState::start_in_place`,
            /// `State::split_with`), with the settings checked beforehand
            /// ([`crate::BeginPlan`], `const` for `const` settings): neither the table
            /// nor the controller moves through the configuration
            /// ([`crate::FlexCan::begin_in_place`]). A plan made for another module is
            /// [`twocan_core::Error::InvalidArgument`]. On error nothing is written, and
            /// the token and the slot come back.
            ///
            /// `R`, the state's register type, is [`crate::regs::FlexCanRegs`] or the
            /// module's fixed base ([`crate::TokenRegisters`]: `Can0At` for `Can0` ...,
            /// so the per-frame code loads no base, issue 21).
            #[allow(clippy::type_complexity)]
            pub fn begin_in_place<'h, O, L, R>(
                self,
                hw: &'h mut core::mem::MaybeUninit<$crate::FlexCanHw<R, O>>,
                checked: &$crate::BeginPlan<L>,
                primary: &[twocan_core::Filter],
                secondary: &[twocan_core::Filter],
                slot: &'static mut L::Table,
            ) -> Result<
                &'h mut $crate::FlexCanHw<R, O>,
                (Self, $crate::BeginError, &'static mut L::Table),
            >
            where
                L: $crate::layout::Layout,
                O: $crate::options::Options<Layout = L, Table = &'static mut L::Table>,
                R: $crate::TokenRegisters<Self>,
            {
                let Some(regs) = self.checked_regs(checked) else {
                    return Err((
                        self,
                        $crate::BeginError::Hardware(twocan_core::Error::InvalidArgument),
                        slot,
                    ));
                };
                $crate::FlexCan::begin_in_place(
                    hw,
                    regs,
                    &mut $system(),
                    checked,
                    primary,
                    secondary,
                    slot,
                )
                .map_err(|(e, slot)| (self, e, slot))
            }

            /// [`Self::begin_planned`] writing the split controller **in place** into
            /// `hw` ([`crate::FlexCan::begin_checked_in_place`]), over the state's
            /// register type `R` as [`Self::begin_in_place`] (the module's fixed base
            /// for a lean state). On error nothing is written and the token comes back.
            pub fn begin_planned_in_place<'h, O, R>(
                self,
                hw: &'h mut core::mem::MaybeUninit<$crate::FlexCanHw<R, O>>,
                checked: &$crate::BeginPlan<O::Layout>,
                table: $crate::installed::PlannedTable,
            ) -> Result<&'h mut $crate::FlexCanHw<R, O>, (Self, $crate::BeginError)>
            where
                O: $crate::options::Options<Table = $crate::installed::PlannedTable>,
                R: $crate::TokenRegisters<Self>,
            {
                let Some(regs) = self.checked_regs(checked) else {
                    return Err((
                        self,
                        $crate::BeginError::Hardware(twocan_core::Error::InvalidArgument),
                    ));
                };
                $crate::FlexCan::begin_checked_in_place(hw, regs, &mut $system(), checked, table)
                    .map_err(|e| (self, e))
            }

            /// `begin` with a filter table planned at compile time
            /// ([`crate::const_plan!`]) and settings checked beforehand
            /// ([`crate::BeginPlan`], `const` for `const` settings), giving the split
            /// controller with the options `O` ([`crate::options::Lean`]): the
            /// initialization sequence alone ([`crate::FlexCan::begin_checked`]). A
            /// plan made for another module is [`twocan_core::Error::InvalidArgument`];
            /// on error the token comes back with the reason.
            pub fn begin_planned<O>(
                self,
                checked: &$crate::BeginPlan<O::Layout>,
                table: $crate::installed::PlannedTable,
            ) -> Result<$crate::FlexCanHw<$crate::regs::FlexCanRegs, O>, (Self, $crate::BeginError)>
            where
                O: $crate::options::Options<Table = $crate::installed::PlannedTable>,
            {
                let Some(regs) = self.checked_regs::<_, $crate::regs::FlexCanRegs>(checked) else {
                    return Err((
                        self,
                        $crate::BeginError::Hardware(twocan_core::Error::InvalidArgument),
                    ));
                };
                $crate::FlexCan::begin_checked(regs, &mut $system(), checked, table)
                    .map_err(|e| (self, e))
            }
        }
    };
}

pub(crate) use token_begin;

/// Defines `end_split` on `$token` (the way back from `begin_in` / `begin_planned`),
/// whose chip-level registers `$system()` gives.
macro_rules! token_end {
    ($token:ident, $system:ident) => {
        impl $token {
            /// The way back from [`Self::begin_in`] / [`Self::begin_planned`], after
            /// `rt::IrqState::stop` or `State::unsplit`: stops the module, releases its
            /// pins and clock gate ([`crate::FlexCanHw::end`]) and gives the token and
            /// the table back (a `FullInSlot` controller's `static` table, to begin into
            /// again), over either register handle of the token
            /// ([`crate::TokenRegisters`]). A controller of another module is
            /// [`twocan_core::Error::InvalidArgument`]; either error gives the
            /// controller back.
            #[allow(clippy::result_large_err, clippy::type_complexity)]
            pub fn end_split<O: $crate::options::Options, R: $crate::TokenRegisters<$token>>(
                hw: $crate::FlexCanHw<R, O>,
            ) -> Result<($token, O::Table), ($crate::FlexCanHw<R, O>, twocan_core::Error)> {
                if hw.target() != $token::returned().target() {
                    return Err((hw, twocan_core::Error::InvalidArgument));
                }
                hw.end(&mut $system())
                    .map(|(_, table)| ($token::returned(), table))
            }
        }
    };
}

pub(crate) use token_end;
