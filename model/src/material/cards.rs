//! Material cards: the values and their sources, nothing else (the law that reads them is
//! `material`; docs/materials.md gives each value with its paper, table and page).

use super::{Branch, Breakdown, Card, MAX_BRANCHES};

const NO_BRANCH: Branch = Branch::NONE;

/// 3M VHB 4905 (acrylic), the board's card: neo-Hookean equilibrium branch and three Maxwell
/// branches, as fitted to VHB 4910 (the same acrylic, thicker) by Wang et al.
pub const VHB_4905: Card = Card {
    name: "VHB-4905",
    g_eq_mpa: 0.015_36,
    branches: [
        Branch { g_mpa: 0.026_06, tau_s: 0.61 },
        Branch { g_mpa: 0.026_53, tau_s: 6.56 },
        Branch { g_mpa: 0.010_83, tau_s: 61.25 },
    ],
    branch_count: 3,
    eps_r: 4.8,
    breakdown: Breakdown { field0_v_per_um: 18.0, stretch_exponent: 0.0 },
    source: "Wang, Decker, Henann, Chester, J. Mech. Phys. Solids 95 (2016) (moduli, times, eps_r); breakdown: lowest unstretched VHB figure",
};

/// The paper's card as printed: G = 0.6 MPa, elastic. Kept to reproduce the paper's scenes,
/// never a board's card. The film is the paper's VHB 4905: its breakdown field is the highest
/// reported unstretched VHB 4905 figure (the board's card takes the lowest).
pub const PAPER_ELASTIC: Card = Card {
    name: "paper-elastic",
    g_eq_mpa: 0.6,
    branches: [NO_BRANCH; MAX_BRANCHES],
    branch_count: 0,
    eps_r: 4.7,
    breakdown: Breakdown { field0_v_per_um: 35.0, stretch_exponent: 0.0 },
    source: "the paper (G = 0.6 MPa, nu = 0.49, eps_r = 4.7); breakdown: Smirnov et al., Technical Physics 2018 (VHB 4905, unstretched)",
};

/// Wacker Elastosil Film 2030 (silicone): nearly elastic and stiffer than the acrylic.
pub const ELASTOSIL_2030: Card = Card {
    name: "Elastosil-2030",
    g_eq_mpa: 0.33,
    branches: [Branch { g_mpa: 0.02, tau_s: 0.5 }, NO_BRANCH, NO_BRANCH],
    branch_count: 1,
    eps_r: 2.8,
    breakdown: Breakdown { field0_v_per_um: 80.0, stretch_exponent: 0.0 },
    source: "Wacker Elastosil Film 2030 data sheet (eps_r, breakdown); modulus: placeholder pending sources",
};

/// Every card, for reports and the console.
pub const CARDS: [&Card; 3] = [&VHB_4905, &PAPER_ELASTIC, &ELASTOSIL_2030];
