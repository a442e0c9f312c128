r"""Camera (thesis section 2.3): pinhole projection, reconstruction filters and film.

- `_pinhole`: coordinate spaces, `look_at`, the projection matrices of eq. 2.28-2.30,
  `PinholeCamera`, `generate_ray` and its inverse `project` (section 2.3.1);
- `_orthographic`, `_thinlens`: `OrthographicCamera` (parallel rays) and `ThinLensCamera`
  (depth of field, two aperture variates per sample), Mitsuba's `orthographic` and `thinlens`;
- `_filters`: box, tent, Gaussian, Mitchell-Netravali and Lanczos filters with filter
  importance sampling (section 2.3.2, eq. 2.31-2.35);
- `_film`: spectral samples to XYZ, per-pixel accumulation (eq. 2.35) and splatting (eq. 2.34),
  development to linear RGB;
- `_io`: OpenEXR (RGB and spectral) and sRGB PNG files, written atomically; Radiance RGBE read.

Conventions (Mitsuba 3's, which the reference scenes use):

- camera space has $+z$ forward, $+y$ up and $+x$ towards the image's **left**; a camera's
  `to_world` is `look_at(origin, target, up)` (the Cornell box: `diag(-1, 1, -1)` plus the
  translation $(0, 0, 3.9)$, so the red wall $x = -1$ is on the image's left);
- image space (NDC) is the view frustum mapped onto $[-1, 1]^3$ by thesis eq. 2.30;
- raster coordinates are continuous pixels, $(0, 0)$ the top-left image corner, pixel
  centres at half-integers: $x = W (1 - x_\mathrm{ndc})/2$, $y = H (1 - y_\mathrm{ndc})/2$;
- filters are normalised to unit integral; `sample` returns offsets $\propto |f|$ and
  weights $f/p$ (thesis eq. 2.35);
- the film's XYZ are $\int L \bar{\mathbf{x}}\,\mathrm{d}\lambda / \int \bar{y}\,\mathrm{d}\lambda$
  (Mitsuba's spectral film normalisation: a constant spectrum $L = 1$ gives $Y = 1$).
"""

from .._image_files import (
    read_exr as read_exr,
    read_hdr as read_hdr,
    read_spectral_exr as read_spectral_exr,
    spectral_channel_name as spectral_channel_name,
    write_exr as write_exr,
    write_png as write_png,
    write_spectral_exr as write_spectral_exr,
)
from ._base import (
    AbstractCamera as AbstractCamera,
    CameraWiSample as CameraWiSample,
)
from ._film import (
    Film as Film,
    SpectralResponse as SpectralResponse,
    film_add_samples as film_add_samples,
    film_add_XYZ as film_add_XYZ,
    film_develop as film_develop,
    film_develop_spectral as film_develop_spectral,
    film_merge as film_merge,
    film_samples_to_spectral_bins as film_samples_to_spectral_bins,
    film_samples_to_XYZ as film_samples_to_XYZ,
    spectral_bin_centres as spectral_bin_centres,
    splat_samples as splat_samples,
)
from ._filters import (
    AbstractFilter as AbstractFilter,
    BoxFilter as BoxFilter,
    GaussianFilter as GaussianFilter,
    LanczosFilter as LanczosFilter,
    MitchellFilter as MitchellFilter,
    TentFilter as TentFilter,
)
from ._orthographic import OrthographicCamera as OrthographicCamera
from ._pinhole import (
    PinholeCamera as PinholeCamera,
    fov_from_focal_length_deg as fov_from_focal_length_deg,
    fov_x_deg as fov_x_deg,
    generate_ray as generate_ray,
    look_at as look_at,
    perspective as perspective,
    perspective_frustum as perspective_frustum,
    project as project,
)
from ._thinlens import ThinLensCamera as ThinLensCamera
