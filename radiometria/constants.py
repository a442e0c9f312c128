"""Physical and CIE constants: exact SI 2019 values and what derives from them.

Every derived constant is computed from the defining ones, never retyped (style.md section 3).
All values are Python floats, so they never fix the dtype of a computation (style.md section 10).

The thesis (eq. 1.25) prints the older CODATA values h = 6.626176e-34 J s and
k = 1.380662e-23 J/K. Since the 2019 redefinition of the SI, h, c and k_B are exact by
definition; this module uses the exact values, which differ from the thesis's in the fifth
significant digit (relative 1.5e-6 for h, 2.6e-6 for k). Planck radiances computed here therefore
differ from ones computed with the thesis's printed constants by a few parts per million.

??? cite "References"
    `BIPM2019` (the SI Brochure, 9th ed., table 1); `Mohr2025` (CODATA 2022) for mu_0;
    `CIE2018` (CIE 015:2018) for K_m and K_m' and the visible range; `Pharr2023` section 4.5
    (`Lambda_min`, `Lambda_max`).
"""

import math

# --- Defining constants of the SI (2019), exact -------------------------------------------
PLANCK = 6.62607015e-34  # J s, exact (SI 2019)
SPEED_OF_LIGHT = 299792458.0  # m s^-1, exact (SI 2019)
BOLTZMANN = 1.380649e-23  # J K^-1, exact (SI 2019)
K_CD = 683.0  # lm W^-1, luminous efficacy of 540e12 Hz radiation, exact (SI 2019)
FREQUENCY_K_CD = 540e12  # Hz, the frequency at which K_CD is defined (SI 2019)

# --- Electromagnetic constants (thesis section 1.1) ------------------------------------------
# Since the 2019 redefinition of the SI, the magnetic constant mu_0 is measured, no longer exact
# (4 pi 1e-7 before). CODATA 2022 value (`Mohr2025`, relative standard uncertainty 1.6e-10),
# the one scipy.constants uses; CODATA 2018 (`Tiesinga2021`) gave 1.25663706212e-6.
VACUUM_PERMEABILITY = 1.25663706127e-6  # N A^-2, mu_0 (CODATA 2022, not exact since SI 2019)
# eps_0 = 1 / (mu_0 c^2)  (thesis section 1.1)
VACUUM_PERMITTIVITY = 1.0 / (VACUUM_PERMEABILITY * SPEED_OF_LIGHT**2)  # F m^-1

# --- Derived radiometric constants --------------------------------------------------------
# Stefan-Boltzmann: sigma = 2 pi^5 k^4 / (15 h^3 c^2)  (thesis eq. 1.22)
STEFAN_BOLTZMANN = (
    2.0 * math.pi**5 * BOLTZMANN**4 / (15.0 * PLANCK**3 * SPEED_OF_LIGHT**2)
)  # W m^-2 K^-4
# First radiation constant for spectral radiance, c_1L = 2 h c^2 (thesis eq. 1.24)
C1L = 2.0 * PLANCK * SPEED_OF_LIGHT**2  # W m^2 sr^-1
# First radiation constant for spectral exitance, c_1 = 2 pi h c^2 = pi c_1L
C1 = math.pi * C1L  # W m^2
# Second radiation constant, c_2 = h c / k
C2 = PLANCK * SPEED_OF_LIGHT / BOLTZMANN  # m K
# Wien's displacement laws. The peak of Planck's law per unit wavelength is at x = c_2/(lambda T)
# solving x = 5 (1 - e^-x); per unit frequency at x = h nu/(k T) solving x = 3 (1 - e^-x). The
# closed forms are n + W_0(-n e^-n) (Lambert W); `wien_root` evaluates them by Newton iteration.


def wien_root(n: int) -> float:
    """The positive root of x = n (1 - exp(-x)) for n = 3 (frequency) or 5 (wavelength)."""
    x = float(n)
    for _ in range(50):
        x -= (x - n * (1.0 - math.exp(-x))) / (1.0 - n * math.exp(-x))
    return x


WIEN_X = wien_root(5)  # dimensionless, about 4.965114231744276
WIEN_DISPLACEMENT = C2 / WIEN_X  # m K, 2.897771955e-3 (CODATA 2018, exact)
WIEN_FREQUENCY_X = wien_root(3)  # dimensionless, about 2.821439372122079
WIEN_FREQUENCY_DISPLACEMENT = WIEN_FREQUENCY_X * BOLTZMANN / PLANCK  # Hz K^-1, 5.878925757e10

# --- Photometric constants ------------------------------------------------------------------
# The wavelength of 540 THz radiation is 555.171 nm in vacuum and 555.016 nm in standard air;
# the CIE tables of V(lambda) are given against wavelengths in standard air.
WAVELENGTH_K_CD_NM = SPEED_OF_LIGHT / FREQUENCY_K_CD * 1e9  # nm, 555.171 nm (in vacuum)
WAVELENGTH_K_CD_AIR_NM = 555.016  # nm, in standard air (CIE 015:2018)
# Maximum photopic luminous efficacy K_m = K_cd / V(555.016 nm). CIE 015:2018 states
# K_m = 683.002 lm W^-1 at 555 nm, because V(lambda) is tabulated with its peak 1 at 555 nm
# and V(555.016 nm) = 0.999997 by interpolation; the thesis (section 2.1) quotes this value.
K_M = 683.002  # lm W^-1, photopic, at 555 nm (CIE 015:2018, thesis section 2.1)
# Maximum scotopic luminous efficacy K'_m = K_cd / V'(555.016 nm) = 683 / 0.40175 = 1700.06
# lm W^-1 at 507 nm (CIE 015:2018); V'(555.016 nm) by linear interpolation of the CIE 1951 table.
# tests/test_constants.py re-derives both K_m and K'_m from the packaged tables.
K_M_SCOTOPIC = 1700.06  # lm W^-1, scotopic, at 507 nm (CIE 015:2018)

# --- The visible range ---------------------------------------------------------------------
# The wavelength range of the CIE 1931 and 1964 colour-matching functions and of V(lambda)
# (CIE 015:2018 tables, 360-830 nm at 1 nm), which pbrt-v4 also samples and upsamples over
# (`Lambda_min`, `Lambda_max`, Pharr et al. 2023, section 4.5). The CIE tables take every
# weighting function as zero outside it.
VISIBLE_WAVELENGTH_MIN_NM = 360.0  # nm (CIE 015:2018; pbrt-v4 `Lambda_min`)
VISIBLE_WAVELENGTH_MAX_NM = 830.0  # nm (CIE 015:2018; pbrt-v4 `Lambda_max`)

# --- Unit conversions: the only place where nm and m meet ------------------------------------
NM_PER_M = 1e9  # nm m^-1
M_PER_NM = 1e-9  # m nm^-1
