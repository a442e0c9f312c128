"""`radiometria.constants` against CODATA / SI 2019 (via `scipy.constants`) and the CIE tables."""

import math

import numpy as np
import pytest
import scipy.constants as sc

from radiometria import constants as c


def _codata(name: str) -> float:
    value, _unit, uncertainty = sc.physical_constants[name]
    assert uncertainty == 0.0, f"{name} should be exact since SI 2019"
    return value


def test_constants_defining_constants_are_exact_si_2019():
    assert c.PLANCK == sc.h == _codata("Planck constant")
    assert c.SPEED_OF_LIGHT == sc.c == _codata("speed of light in vacuum")
    assert c.BOLTZMANN == sc.k == _codata("Boltzmann constant")
    assert c.K_CD == _codata("luminous efficacy")
    assert c.FREQUENCY_K_CD == 540e12


@pytest.mark.parametrize(
    ("value", "name"),
    [
        (c.STEFAN_BOLTZMANN, "Stefan-Boltzmann constant"),
        (c.C1, "first radiation constant"),
        (c.C1L, "first radiation constant for spectral radiance"),
        (c.C2, "second radiation constant"),
        (c.WIEN_DISPLACEMENT, "Wien wavelength displacement law constant"),
    ],
)
def test_constants_derived_match_codata(value, name):
    # Derived from exact constants, so CODATA lists them as exact; they agree to rounding.
    assert value == pytest.approx(_codata(name), rel=4e-16)


def test_constants_wien_root():
    x = c.WIEN_X
    assert x == pytest.approx(5.0 * (1.0 - math.exp(-x)), rel=1e-15)
    assert x == pytest.approx(4.965114231744276, rel=1e-15)
    # The frequency form of Wien's law has the root of x = 3 (1 - e^-x).
    assert c.WIEN_FREQUENCY_X == pytest.approx(
        3.0 * (1.0 - math.exp(-c.WIEN_FREQUENCY_X)), rel=1e-15
    )
    assert c.WIEN_FREQUENCY_DISPLACEMENT == pytest.approx(
        _codata("Wien frequency displacement law constant"), rel=4e-16
    )


def test_constants_unit_conversions():
    assert c.NM_PER_M == 1e9
    assert c.M_PER_NM == 1e-9
    # lambda = c / nu in vacuum; CIE quotes 555.016 nm for the same frequency in standard air.
    assert c.WAVELENGTH_K_CD_NM == pytest.approx(555.1712185185185, rel=1e-15)


def _v_at_k_cd(vision: str) -> float:
    """V or V' at 555.016 nm, the wavelength of 540 THz in standard air (CIE), interpolated."""
    from radiometria.photometry import luminous_efficiency_table

    wavelengths_nm, values = (np.asarray(a) for a in luminous_efficiency_table(vision))
    return float(np.interp(555.016, wavelengths_nm, values))


def test_constants_k_m_photopic_from_k_cd():
    # K_m = K_cd V(555 nm) / V(555.016 nm) = 683.002 lm/W (CIE S 017, term 17-21-092).
    assert c.K_M == round(c.K_CD / _v_at_k_cd("photopic"), 3) == 683.002


def test_constants_k_m_scotopic_from_k_cd():
    # K'_m = K_cd V'(507 nm) / V'(555.016 nm): the scotopic curve also gives 683 lm/W at 540 THz.
    assert round(c.K_CD / _v_at_k_cd("scotopic"), 2) == pytest.approx(c.K_M_SCOTOPIC, abs=0.005)


def test_constants_vacuum_permeability_and_permittivity_match_scipy():
    # mu_0 is measured since SI 2019: CODATA 2022 (SciPy >= 1.15 too) gives 1.25663706127(20)e-6
    # N A^-2. A later CODATA adjustment moves it by a few 1e-10 relative, hence rel=1e-9.
    value, unit, uncertainty = sc.physical_constants["vacuum mag. permeability"]
    assert unit == "N A^-2" and uncertainty > 0.0
    assert c.VACUUM_PERMEABILITY == pytest.approx(value, rel=1e-9)
    # eps_0 = 1 / (mu_0 c^2), derived, not retyped.
    value, unit, _ = sc.physical_constants["vacuum electric permittivity"]
    assert unit == "F m^-1"
    assert c.VACUUM_PERMITTIVITY == pytest.approx(value, rel=1e-9)
    if sc.mu_0 == 1.25663706127e-6:  # SciPy with CODATA 2022, the adjustment used here
        assert c.VACUUM_PERMEABILITY == sc.mu_0
        # CODATA prints eps_0 to 11 digits: equal to rounding.
        assert c.VACUUM_PERMITTIVITY == pytest.approx(sc.epsilon_0, rel=1e-11)
    assert c.VACUUM_PERMITTIVITY * c.VACUUM_PERMEABILITY * c.SPEED_OF_LIGHT**2 == pytest.approx(
        1.0, rel=1e-15
    )
    # Within its uncertainty of the pre-2019 exact value 4 pi 1e-7.
    assert c.VACUUM_PERMEABILITY == pytest.approx(4e-7 * math.pi, rel=1e-9)
