"""Colorimetry (thesis section 2.2): CIE observers, tristimulus values, colour spaces.

- CIE tables with provenance (`get_cmfs`, `get_illuminant`, `daylight_spd`; `_data` docstring);
- spectrum -> XYZ, emissive and reflective (`sd_to_XYZ`, `tristimulus_weights`; thesis eq.
  2.12-2.19), XYZ <-> xyY <-> xy (eq. 2.20-2.22);
- the CIE 1931 RGB system: spectrum -> RGB with the r̄ḡb̄ CMFs (`sd_to_CIE_RGB`, eq.
  2.6-2.9), its luminance (`CIE_RGB_luminance`, eq. 2.10), RGB <-> XYZ (eq. 2.11);
- CIELAB / LCh, CIELUV / LCHuv, CIE 1960 uv and 1976 u'v', colour differences Delta E
  1976 / 1994 / 2000;
- RGB colour spaces with derived matrices and transfer functions, chromatic adaptation,
  sRGB (thesis 2.2.2);
- Planckian locus and correlated colour temperature (thesis 2.2.1, table 2.1).
"""

from ._adaptation import (
    CHROMATIC_ADAPTATION_TRANSFORMS as CHROMATIC_ADAPTATION_TRANSFORMS,
    chromatic_adaptation as chromatic_adaptation,
    matrix_chromatic_adaptation as matrix_chromatic_adaptation,
)
from ._data import (
    TabulatedSpectra as TabulatedSpectra,
    get_cmfs as get_cmfs,
    get_illuminant as get_illuminant,
)
from ._daylight import (
    daylight_locus_xy as daylight_locus_xy,
    daylight_M1_M2 as daylight_M1_M2,
    daylight_spd as daylight_spd,
)
from ._difference import (
    delta_E_CIE1976 as delta_E_CIE1976,
    delta_E_CIE1994 as delta_E_CIE1994,
    delta_E_CIE2000 as delta_E_CIE2000,
)
from ._models import (
    CIE_RGB_to_XYZ as CIE_RGB_to_XYZ,
    Lab_to_LCh as Lab_to_LCh,
    Lab_to_XYZ as Lab_to_XYZ,
    LCh_to_Lab as LCh_to_Lab,
    LCHuv_to_Luv as LCHuv_to_Luv,
    Luv_to_LCHuv as Luv_to_LCHuv,
    Luv_to_uv as Luv_to_uv,
    Luv_to_XYZ as Luv_to_XYZ,
    Luv_uv_to_xy as Luv_uv_to_xy,
    UCS_uv_to_xy as UCS_uv_to_xy,
    XYZ_to_CIE_RGB as XYZ_to_CIE_RGB,
    XYZ_to_Lab as XYZ_to_Lab,
    XYZ_to_Luv as XYZ_to_Luv,
    XYZ_to_Luv_uv as XYZ_to_Luv_uv,
    XYZ_to_UCS_uv as XYZ_to_UCS_uv,
    uv_to_Luv as uv_to_Luv,
    xy_to_Luv_uv as xy_to_Luv_uv,
    xy_to_UCS_uv as xy_to_UCS_uv,
)
from ._rgb import (
    RGB_COLOURSPACES as RGB_COLOURSPACES,
    RGB_to_RGB as RGB_to_RGB,
    RGB_to_XYZ as RGB_to_XYZ,
    RGBColourspace as RGBColourspace,
    XYZ_to_RGB as XYZ_to_RGB,
    XYZ_to_sRGB as XYZ_to_sRGB,
    bt709_oetf as bt709_oetf,
    bt709_oetf_inverse as bt709_oetf_inverse,
    gamma_decoding as gamma_decoding,
    gamma_encoding as gamma_encoding,
    get_colourspace as get_colourspace,
    matrix_RGB_to_RGB as matrix_RGB_to_RGB,
    normalised_primary_matrix as normalised_primary_matrix,
    romm_decoding as romm_decoding,
    romm_encoding as romm_encoding,
    srgb_eotf as srgb_eotf,
    srgb_eotf_inverse as srgb_eotf_inverse,
    sRGB_to_XYZ as sRGB_to_XYZ,
)
from ._temperature import (
    CCT_to_uv as CCT_to_uv,
    CCT_to_xy as CCT_to_xy,
    planckian_locus_uv as planckian_locus_uv,
    planckian_table as planckian_table,
    uv_to_CCT as uv_to_CCT,
    xy_to_CCT as xy_to_CCT,
)
from ._tristimulus import (
    CIE_RGB_luminance as CIE_RGB_luminance,
    XYZ_to_xy as XYZ_to_xy,
    XYZ_to_xyY as XYZ_to_xyY,
    sd_to_CIE_RGB as sd_to_CIE_RGB,
    sd_to_XYZ as sd_to_XYZ,
    tristimulus_weights as tristimulus_weights,
    xy_to_xyY as xy_to_xyY,
    xy_to_XYZ as xy_to_XYZ,
    xyY_to_xy as xyY_to_xy,
    xyY_to_XYZ as xyY_to_XYZ,
)
