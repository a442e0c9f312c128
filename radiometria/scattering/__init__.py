"""Surfaces (thesis ch. 3): reflection, refraction, Fresnel equations and BxDFs.

- `_directions`: reflect / refract (thesis eq. 3.7-3.12), shading frames, spherical coordinates;
- `_fresnel`: Fresnel equations for dielectrics and conductors (eq. 3.13-3.18), Schlick;
- `_ior`: spectral indices of refraction (Sellmeier glasses and water, tabulated Au/Ag/Cu/Al),
  the relative complex index of two absorbing media (footnote 18);
- `_microfacet`: the Trowbridge-Reitz (GGX) and Beckmann distributions with visible-normal sampling;
- `_bxdfs`: BxDFs (eq. 3.4) with `f`, `sample_f`, `pdf`: Lambertian, Oren-Nayar, diffuse
  transmission, retroreflection, smooth and rough conductor and dielectric, two-sided wrapper;
- `_plastic`, `_thin_dielectric`, `_blend`: smooth and rough plastic, the thin dielectric slab,
  blends of two BxDFs and partly transparent (masked) surfaces (Mitsuba 3's plugins);
- `_principled`: the principled (Disney) BSDF as Mitsuba 3 implements it;
- `_properties`: absorptance from eq. 3.2, the flux-weighted -ances of table 3.1, slab and
  thick-layer properties and the -ivities of the glossary;
- `_reflectance`: the reflectance quantities of table 3.2 by Monte Carlo.

Conventions: the normal points out of the surface; in the local shading frame it is +z; all
directions point away from the surface and are unit vectors (assumed, not checked).
"""

from ._blend import BlendBxDF as BlendBxDF, MaskBxDF as MaskBxDF
from ._bxdfs import (
    AbstractBxDF as AbstractBxDF,
    BSDFSample as BSDFSample,
    ConductorBxDF as ConductorBxDF,
    DielectricBxDF as DielectricBxDF,
    DiffuseBxDF as DiffuseBxDF,
    DiffuseTransmissionBxDF as DiffuseTransmissionBxDF,
    OrenNayarBxDF as OrenNayarBxDF,
    RetroreflectiveBxDF as RetroreflectiveBxDF,
    RoughConductorBxDF as RoughConductorBxDF,
    RoughDielectricBxDF as RoughDielectricBxDF,
    TwoSidedBxDF as TwoSidedBxDF,
)
from ._directions import (
    Frame as Frame,
    abs_cos_theta as abs_cos_theta,
    coordinate_system as coordinate_system,
    cos2_theta as cos2_theta,
    cos_phi as cos_phi,
    cos_theta as cos_theta,
    face_forward as face_forward,
    normalize as normalize,
    reflect as reflect,
    refract as refract,
    same_hemisphere as same_hemisphere,
    sin2_theta as sin2_theta,
    sin_phi as sin_phi,
    sin_theta as sin_theta,
    spherical_direction as spherical_direction,
    spherical_phi as spherical_phi,
    spherical_theta as spherical_theta,
    tan2_theta as tan2_theta,
    tan_theta as tan_theta,
    to_local as to_local,
    to_world as to_world,
)
from ._fresnel import (
    fresnel_complex as fresnel_complex,
    fresnel_conductor as fresnel_conductor,
    fresnel_conductor_polarized as fresnel_conductor_polarized,
    fresnel_dielectric as fresnel_dielectric,
    fresnel_dielectric_amplitudes as fresnel_dielectric_amplitudes,
    fresnel_dielectric_polarized as fresnel_dielectric_polarized,
    fresnel_dielectric_transmittance as fresnel_dielectric_transmittance,
    fresnel_schlick as fresnel_schlick,
    fresnel_schlick_f0 as fresnel_schlick_f0,
)
from ._ior import (
    CONDUCTORS as CONDUCTORS,
    DIELECTRICS as DIELECTRICS,
    TabulatedIOR as TabulatedIOR,
    conductor_ior as conductor_ior,
    dielectric_ior as dielectric_ior,
    get_conductor as get_conductor,
    relative_complex_ior as relative_complex_ior,
    sellmeier as sellmeier,
)
from ._microfacet import (
    BeckmannDistribution as BeckmannDistribution,
    TrowbridgeReitzDistribution as TrowbridgeReitzDistribution,
    roughness_to_alpha as roughness_to_alpha,
)
from ._plastic import (
    PlasticBxDF as PlasticBxDF,
    RoughPlasticBxDF as RoughPlasticBxDF,
    fresnel_diffuse_reflectance as fresnel_diffuse_reflectance,
    rough_plastic_tables as rough_plastic_tables,
)
from ._principled import (
    PrincipledBxDF as PrincipledBxDF,
    PrincipledThinBxDF as PrincipledThinBxDF,
    principled_eta as principled_eta,
)
from ._properties import (
    absorptance as absorptance,
    absorptivity as absorptivity,
    flux_weighted_absorptance as flux_weighted_absorptance,
    flux_weighted_reflectance as flux_weighted_reflectance,
    flux_weighted_transmittance as flux_weighted_transmittance,
    reflectivity_kubelka1931 as reflectivity_kubelka1931,
    slab_reflectance_transmittance as slab_reflectance_transmittance,
    transmissivity as transmissivity,
)
from ._reflectance import (
    Cone as Cone,
    biconical_reflectance as biconical_reflectance,
    bidirectional_reflectance as bidirectional_reflectance,
    bihemispherical_reflectance as bihemispherical_reflectance,
    conical_directional_reflectance as conical_directional_reflectance,
    conical_hemispherical_reflectance as conical_hemispherical_reflectance,
    directional_conical_reflectance as directional_conical_reflectance,
    directional_hemispherical_reflectance as directional_hemispherical_reflectance,
    hemispherical_conical_reflectance as hemispherical_conical_reflectance,
    hemispherical_directional_reflectance as hemispherical_directional_reflectance,
    normalised_hemispherical_directional_reflectance as normalised_hemispherical_directional_reflectance,  # noqa: E501
)
from ._thin_dielectric import (
    ThinDielectricBxDF as ThinDielectricBxDF,
    thin_slab_reflectance as thin_slab_reflectance,
)
