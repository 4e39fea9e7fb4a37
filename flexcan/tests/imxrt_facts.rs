//! The driver's i.MX RT1062 facts against the `imxrt-ral` register blocks (NXP SVD,
//! feature `imxrt1062`), as `regmap.rs` checks the Kinetis ones against their PACs:
//! module bases, interrupt numbers, the CCM clock root fields and clock gates, and
//! every IOMUXC register the Teensy 4 pins use.

use core::mem::offset_of;

use imxrt_ral::ccm::RegisterBlock as Ccm;
use imxrt_ral::iomuxc::RegisterBlock as Iomuxc;
use twocan_flexcan::imxrt::{ccm, pads};
use twocan_flexcan::{Board, Chip, Instance, Target};

fn ccm_reg(offset: usize) -> usize {
    imxrt_ral::ccm::CCM as usize + offset
}

fn iomuxc_reg(offset: usize) -> usize {
    imxrt_ral::iomuxc::IOMUXC as usize + offset
}

#[test]
fn bases_and_interrupts() {
    let chip = Chip::Imxrt1062;
    assert_eq!(
        Instance::Can1.base(chip),
        Some(imxrt_ral::can::CAN1 as usize)
    );
    assert_eq!(
        Instance::Can2.base(chip),
        Some(imxrt_ral::can::CAN2 as usize)
    );
    assert_eq!(
        Instance::Can3.base(chip),
        Some(imxrt_ral::can3::CAN3 as usize)
    );
    assert_eq!(Instance::Can0.base(chip), None);
    for (i, irq) in [
        (Instance::Can1, imxrt_ral::Interrupt::CAN1),
        (Instance::Can2, imxrt_ral::Interrupt::CAN2),
        (Instance::Can3, imxrt_ral::Interrupt::CAN3),
    ] {
        let irqs = Target::new(Board::Teensy41, i).irqs().unwrap();
        assert!(irqs.is_single_line());
        assert_eq!(irqs.message, irq as u16, "{i:?}");
    }
}

/// The window of a fixed-base register type: (base, start, end).
fn window<const B: usize, const E: usize, const S: usize>(
    _: std::marker::PhantomData<twocan_core::Fixed<B, E, S>>,
) -> (usize, usize, usize) {
    (B, S, E)
}

#[test]
fn fixed_register_types_are_at_the_ral_s_addresses_with_the_rt1062_window() {
    use std::marker::PhantomData as T;
    use twocan_flexcan::imxrt::{Can1At, Can2At, Can3At};
    use twocan_flexcan::regs::IMXRT_BLOCK_END;
    let end = IMXRT_BLOCK_END;
    assert_eq!(window(T::<Can1At>), (imxrt_ral::can::CAN1 as usize, 0, end));
    assert_eq!(window(T::<Can2At>), (imxrt_ral::can::CAN2 as usize, 0, end));
    assert_eq!(
        window(T::<Can3At>),
        (imxrt_ral::can3::CAN3 as usize, 0, end)
    );
    // The window ends after RXIMR63, the last individual mask (NXP SVD).
    assert_eq!(
        offset_of!(imxrt_ral::can3::RegisterBlock, RXIMR) + 64 * 4,
        end
    );
}

#[test]
fn clock_root_and_gates() {
    use imxrt_ral::ccm::{CCGR0, CCGR7, CSCMR2};
    assert_eq!(ccm::CCM_CSCMR2, ccm_reg(offset_of!(Ccm, CSCMR2)));
    assert_eq!(ccm::CCM_CCGR0, ccm_reg(offset_of!(Ccm, CCGR0)));
    assert_eq!(ccm::CCM_CCGR7, ccm_reg(offset_of!(Ccm, CCGR7)));
    assert_eq!(ccm::CAN_CLK_SEL.mask(), CSCMR2::CAN_CLK_SEL::mask);
    assert_eq!(ccm::CAN_CLK_PODF.mask(), CSCMR2::CAN_CLK_PODF::mask);
    let chip = Chip::Imxrt1062;
    assert_eq!(
        Instance::Can1.clock_gate(chip),
        Some((ccm::CCM_CCGR0, CCGR0::CG7::mask | CCGR0::CG8::mask))
    );
    assert_eq!(
        Instance::Can2.clock_gate(chip),
        Some((ccm::CCM_CCGR0, CCGR0::CG9::mask | CCGR0::CG10::mask))
    );
    assert_eq!(
        Instance::Can3.clock_gate(chip),
        Some((ccm::CCM_CCGR7, CCGR7::CG3::mask | CCGR7::CG4::mask))
    );
}

#[test]
fn pads_mux_and_daisy() {
    use imxrt_ral::iomuxc::{SW_MUX_CTL_PAD_GPIO_EMC_36 as MUX, SW_PAD_CTL_PAD_GPIO_EMC_36 as PAD};
    let rows = [
        (
            pads::CAN1_TX,
            offset_of!(Iomuxc, SW_MUX_CTL_PAD_GPIO_AD_B1_08),
            offset_of!(Iomuxc, SW_PAD_CTL_PAD_GPIO_AD_B1_08),
        ),
        (
            pads::CAN1_RX,
            offset_of!(Iomuxc, SW_MUX_CTL_PAD_GPIO_AD_B1_09),
            offset_of!(Iomuxc, SW_PAD_CTL_PAD_GPIO_AD_B1_09),
        ),
        (
            pads::CAN2_TX,
            offset_of!(Iomuxc, SW_MUX_CTL_PAD_GPIO_AD_B0_02),
            offset_of!(Iomuxc, SW_PAD_CTL_PAD_GPIO_AD_B0_02),
        ),
        (
            pads::CAN2_RX,
            offset_of!(Iomuxc, SW_MUX_CTL_PAD_GPIO_AD_B0_03),
            offset_of!(Iomuxc, SW_PAD_CTL_PAD_GPIO_AD_B0_03),
        ),
        (
            pads::CAN3_TX,
            offset_of!(Iomuxc, SW_MUX_CTL_PAD_GPIO_EMC_36),
            offset_of!(Iomuxc, SW_PAD_CTL_PAD_GPIO_EMC_36),
        ),
        (
            pads::CAN3_RX,
            offset_of!(Iomuxc, SW_MUX_CTL_PAD_GPIO_EMC_37),
            offset_of!(Iomuxc, SW_PAD_CTL_PAD_GPIO_EMC_37),
        ),
    ];
    for (pin, mux, pad) in rows {
        assert_eq!(pin.mux, iomuxc_reg(mux), "{}", pin.pad);
        assert_eq!(pin.pad_ctl, iomuxc_reg(pad), "{}", pin.pad);
        assert!(pin.alt <= MUX::MUX_MODE::mask >> MUX::MUX_MODE::offset);
    }
    assert_eq!(
        pads::FLEXCAN1_RX_SELECT_INPUT,
        iomuxc_reg(offset_of!(Iomuxc, FLEXCAN1_RX_SELECT_INPUT))
    );
    assert_eq!(
        pads::FLEXCAN2_RX_SELECT_INPUT,
        iomuxc_reg(offset_of!(Iomuxc, FLEXCAN2_RX_SELECT_INPUT))
    );
    assert_eq!(
        pads::CANFD_IPP_IND_CANRX_SELECT_INPUT,
        iomuxc_reg(offset_of!(Iomuxc, CANFD_IPP_IND_CANRX_SELECT_INPUT))
    );
    // Pad control fields.
    assert_eq!(pads::MUX_MODE.mask(), MUX::MUX_MODE::mask);
    assert_eq!(pads::PAD_ODE, PAD::ODE::mask);
    assert_eq!(pads::PAD_PKE, PAD::PKE::mask);
    assert_eq!(pads::PAD_PUE, PAD::PUE::mask);
    assert_eq!(pads::PAD_PUS.mask(), PAD::PUS::mask);
    assert_eq!(pads::PAD_DSE.mask(), PAD::DSE::mask);
    assert_eq!(pads::PAD_SPEED.mask(), PAD::SPEED::mask);
    assert_eq!(pads::PAD_HYS, PAD::HYS::mask);
}
