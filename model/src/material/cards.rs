//! Material cards: the values and their sources, nothing else (the law that reads them is
//! `material`; docs/materials.md gives each value with its paper, table and page).

use super::{Branch, Breakdown, Card, MAX_BRANCHES};

const NO_BRANCH: Branch = Branch::NONE;

/// 3M VHB 4905 (acrylic), the board's card: the softest of three equilibrium fits of the same
/// acrylic (VHB 4910), Wang et al.'s three Maxwell branches and permittivity, and a breakdown
/// field below the measured quasi-static one, flat in stretch (docs/materials.md).
///
/// Sources: G_eq: neo-Hookean fit to Hossain et al. 2012 (Comput. Mater. Sci. 59) equilibrium
/// data, 13.4 kPa, softest of three (Kumar & Lopez-Pamies 2016 Table 2: 14.2 at s=2/3; Wang et
/// al. 2016: 15.36); branches, eps_r: Wang, Decker, Henann, Chester, JMPS 95 (2016), via Stewart
/// & Anand's example codes; breakdown: 18 V/um flat, below Smirnov et al. 2018 (35 V/um
/// unstretched)
pub const VHB_4905: Card = Card {
    name: "VHB-4905",
    g_eq_mpa: 0.013_4,
    branches: [Branch { g_mpa: 0.026_06, tau_s: 0.607_4 }, Branch { g_mpa: 0.026_53, tau_s: 6.56 }, Branch { g_mpa: 0.010_83, tau_s: 61.25 }],
    branch_count: 3,
    eps_r: 4.8,
    breakdown: Breakdown { field0_v_per_um: 18.0 },
    // 3M VHB 4910/4905 technical data sheet: foam density 960 kg/m³
    rho_g_cm3: 0.96,
};

/// The paper's card as printed: G = 0.6 MPa, elastic. Kept to reproduce the paper's scenes,
/// never a board's card. The film is the paper's VHB 4905: its breakdown field is the highest
/// reported unstretched VHB 4905 figure (the board's card takes the lowest).
///
/// Sources: the paper, section II-A (G = 0.6 MPa, nu = 0.49, z0 = 0.5 mm); eps_r 4.7: docs/model.md
/// (the paper prints none); breakdown: Smirnov et al., Technical Physics 2018 (VHB 4905,
/// unstretched, quasi-static: 35 V/um)
pub const PAPER_ELASTIC: Card = Card {
    name: "paper-elastic",
    g_eq_mpa: 0.6,
    branches: [NO_BRANCH; MAX_BRANCHES],
    branch_count: 0,
    eps_r: 4.7,
    breakdown: Breakdown { field0_v_per_um: 35.0 },
    // the paper's film is VHB 4905: its data sheet's 960 kg/m³
    rho_g_cm3: 0.96,
};

/// Wacker Elastosil Film 2030 (silicone): elastic and stiffer than the acrylic.
///
/// Sources: G: Yeoh C10 180.7, C20 -16.7, C30 6.6 kPa (Hoffstadt et al. 2018, via Solano et al.
/// Table 1) at s=2/3; eps_r: -0.28 lambda + 2.76 at lambda=1 (Hodgins & Seelecke 2016, via Solano
/// et al. Eq. 32); breakdown: 70 V/um held-DC lifetime field (Albuquerque & Shea 2021); no
/// relaxation (silicone: negligible viscoelasticity)
// same shape as PAPER_ELASTIC (an elastic card's fields): another film's values
pub const ELASTOSIL_2030: Card = Card {
    name: "Elastosil-2030",
    g_eq_mpa: 0.339_5,
    branches: [NO_BRANCH; MAX_BRANCHES],
    branch_count: 0,
    eps_r: 2.48,
    breakdown: Breakdown { field0_v_per_um: 70.0 },
    // Wacker Elastosil Film 2030 data sheet: density 1.1 g/cm³ (silicone, DIN EN ISO 1183-1 A)
    rho_g_cm3: 1.1,
};

/// Every card, for reports and the console.
pub const CARDS: [&Card; 3] = [&VHB_4905, &PAPER_ELASTIC, &ELASTOSIL_2030];
