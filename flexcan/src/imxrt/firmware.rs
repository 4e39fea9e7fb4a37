//! `begin` and `end` of the Teensy 4.x tokens on the target (`Can1`, `Can2`, `Can3`):
//! the module at its base address, the CCM and IOMUXC by absolute address. The
//! controller is in the RT1062 layout ([`Imxrt1062`]: the ERR005829 workaround, tables
//! up to RFFN 0xF); the in-place and planned forms (`begin_in`, `begin_in_place`,
//! `begin_planned`) take the layout of the options the caller's state names.

use twocan_core::{Error, Filter};

use crate::begin_error::BeginError;
use crate::controller::FlexCan;
use crate::instance::{Can1, Can2, Can3};
use crate::layout::Imxrt1062;
use crate::regs::FlexCanRegs;
use crate::settings::Settings;

/// Volatile access to the CCM and IOMUXC registers `begin` and `end` write, by absolute
/// address (base 0; the window from the CCM, 0x400F_C000, to the end of the IOMUXC,
/// 0x401F_C000).
pub type ImxSystemRegs = twocan_core::Mmio<0x401F_C000, 0x400F_C000>;

pub(crate) fn system() -> ImxSystemRegs {
    // SAFETY: base 0 with absolute offsets, the window CCM..IOMUXC. `begin` and `end`
    // touch only CCM_CSCMR2 and the CCGR of their module (read-modify-writes in a
    // critical section) and the IOMUXC registers of their module's two pads and Rx daisy
    // select, which the token owns; all exist on the RT1062.
    unsafe { ImxSystemRegs::new(0) }
}

macro_rules! begin_end {
    ($token:ident, $name:literal) => {
        impl $token {
            #[doc = concat!("Configures ", $name, " (ACAN `begin`, §15): clock root, gates, pads, then the")]
            /// module, in the RT1062 layout ([`Imxrt1062`]: the ERR005829 reserved
            /// mailbox, `settings.configuration` up to `Filters32_96`); gives the
            /// controller, or the token back with the reason.
            pub fn begin(
                self,
                settings: &Settings,
                primary: &[Filter],
                secondary: &[Filter],
            ) -> Result<FlexCan<FlexCanRegs, Imxrt1062>, (Self, BeginError)> {
                let target = self.target();
                let Some(base) = target.base() else {
                    return Err((self, BeginError::Config(crate::ConfigErrors::NO_SUCH_INSTANCE)));
                };
                // SAFETY: the token is unique (taken once) and consumed here, so this
                // is the only access to the module, at its reference-manual base.
                let regs = unsafe { FlexCanRegs::new(base) };
                FlexCan::<_, Imxrt1062>::begin_with_layout(
                    regs,
                    &mut system(),
                    target,
                    settings,
                    primary,
                    secondary,
                )
                .map_err(|e| (self, e))
            }

            #[doc = concat!("Stops ", $name, ", releases its pads and clock gates ([`FlexCan::end`]) and")]
            /// gives the token back. A controller of another module is
            /// [`Error::InvalidArgument`]; either error gives the controller back.
            #[allow(clippy::result_large_err)]
            pub fn end(
                controller: FlexCan<FlexCanRegs, Imxrt1062>,
            ) -> Result<$token, (FlexCan<FlexCanRegs, Imxrt1062>, Error)> {
                if controller.target() != $token::returned().target() {
                    return Err((controller, Error::InvalidArgument));
                }
                controller
                    .end(&mut system())
                    .map(|_| $token::returned())
            }
        }
    };
}

begin_end!(Can1, "CAN1");
begin_end!(Can2, "CAN2");
begin_end!(Can3, "CAN3");
crate::token_begin::token_begin!(Can1, system);
crate::token_begin::token_begin!(Can2, system);
crate::token_begin::token_begin!(Can3, system);
crate::token_begin::token_end!(Can1, system);
crate::token_begin::token_end!(Can2, system);
crate::token_begin::token_end!(Can3, system);
