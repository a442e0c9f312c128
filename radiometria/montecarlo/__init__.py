"""Monte Carlo and quasi-Monte Carlo (thesis ch. 5-7, app. A and C): samplers, warps, estimators.

The thesis gives chapters 5 (sampling and reconstruction with quasi-random numbers),
6 (Monte Carlo integration) and 7 (variance reduction) as titles only; this subpackage fills them
in from `Pharr2023` (ch. 2 and 8), `Owen2013` and `Veach1997`:

- point sets in [0, 1)^d: `independent`, `stratified`, `latin_hypercube`, `halton`, `sobol`
  (Joe-Kuo direction numbers, scrambled or not), `rank1_lattice`, `kronecker`;
- warps from uniform variates to disks, hemispheres, spheres, cones, triangles, spherical
  triangles, 1D densities, tabulated distributions and visible wavelengths, each as a pbrt-style
  `sample_X` / `X_pdf` / `invert_X_sample` triad;
- estimators that return an `Estimate` (mean, variance, standard error), variance reduction,
  MIS heuristics, and `integrate`;
- statistical tools: `chi2_test`, `pixel_z_test` (an image against a reference) and
  `convergence_study`.
"""

from ._chi2 import Chi2Result as Chi2Result, chi2_test as chi2_test
from ._distributions import (
    PiecewiseConstant1D as PiecewiseConstant1D,
    PiecewiseConstant2D as PiecewiseConstant2D,
    sample_discrete as sample_discrete,
)
from ._estimators import (
    Estimate as Estimate,
    antithetic as antithetic,
    control_variate as control_variate,
    estimate_mean as estimate_mean,
    filter_importance_sampling as filter_importance_sampling,
    importance_sampling as importance_sampling,
    mis_estimate as mis_estimate,
    one_sample_mis as one_sample_mis,
    roulette_and_split as roulette_and_split,
    russian_roulette as russian_roulette,
    stratified_estimate as stratified_estimate,
    weighted_importance_sampling as weighted_importance_sampling,
)
from ._genz import GENZ_FAMILIES as GENZ_FAMILIES, genz as genz
from ._halton import halton as halton
from ._heuristics import (
    balance_heuristic as balance_heuristic,
    mis_weights as mis_weights,
    power_heuristic as power_heuristic,
)
from ._integrate import (
    ConvergenceStudy as ConvergenceStudy,
    convergence_study as convergence_study,
    integrate as integrate,
)
from ._samplers import (
    independent as independent,
    kronecker as kronecker,
    latin_hypercube as latin_hypercube,
    rank1_lattice as rank1_lattice,
    stratified as stratified,
)
from ._sobol import sobol as sobol
from ._warps import (
    cosine_hemisphere_pdf as cosine_hemisphere_pdf,
    exponential_pdf as exponential_pdf,
    invert_cosine_hemisphere_sample as invert_cosine_hemisphere_sample,
    invert_exponential_sample as invert_exponential_sample,
    invert_linear_sample as invert_linear_sample,
    invert_spherical_triangle_sample as invert_spherical_triangle_sample,
    invert_tent_sample as invert_tent_sample,
    invert_uniform_cone_sample as invert_uniform_cone_sample,
    invert_uniform_disk_concentric_sample as invert_uniform_disk_concentric_sample,
    invert_uniform_disk_polar_sample as invert_uniform_disk_polar_sample,
    invert_uniform_hemisphere_sample as invert_uniform_hemisphere_sample,
    invert_uniform_sphere_sample as invert_uniform_sphere_sample,
    invert_uniform_triangle_sample as invert_uniform_triangle_sample,
    invert_visible_wavelengths_sample as invert_visible_wavelengths_sample,
    linear_pdf as linear_pdf,
    sample_cosine_hemisphere as sample_cosine_hemisphere,
    sample_exponential as sample_exponential,
    sample_linear as sample_linear,
    sample_spherical_triangle as sample_spherical_triangle,
    sample_tent as sample_tent,
    sample_uniform_cone as sample_uniform_cone,
    sample_uniform_disk_concentric as sample_uniform_disk_concentric,
    sample_uniform_disk_polar as sample_uniform_disk_polar,
    sample_uniform_hemisphere as sample_uniform_hemisphere,
    sample_uniform_sphere as sample_uniform_sphere,
    sample_uniform_triangle as sample_uniform_triangle,
    sample_visible_wavelengths as sample_visible_wavelengths,
    sample_visible_wavelengths_with_pdf as sample_visible_wavelengths_with_pdf,
    spherical_triangle_area as spherical_triangle_area,
    spherical_triangle_pdf as spherical_triangle_pdf,
    tent_pdf as tent_pdf,
    uniform_cone_pdf as uniform_cone_pdf,
    uniform_disk_pdf as uniform_disk_pdf,
    uniform_hemisphere_pdf as uniform_hemisphere_pdf,
    uniform_sphere_pdf as uniform_sphere_pdf,
    uniform_triangle_pdf as uniform_triangle_pdf,
    visible_wavelengths_pdf as visible_wavelengths_pdf,
)
from ._ztest import ZTestResult as ZTestResult, pixel_z_test as pixel_z_test
