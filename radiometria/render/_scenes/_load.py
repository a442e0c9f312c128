"""Loading scenes: the built-in scenes by name, JSON and Mitsuba 3 XML files by path.

Built-in scenes (`load_scene`):

- `"cornell-box"`: exactly `data/cornell_box.json`, the expansion of Mitsuba 3's
  `cornell_box()` into world-space triangles (36 triangles, 3 diffuse materials, one area
  light of 0.46 x 0.38 = 0.1748 units^2, camera at z = 3.9, 256 x 256 Gaussian film,
  `max_depth` 8).
- `"cornell-box-measured"`: `data/cornell_box_measured.json`, the Cornell Program of Computer
  Graphics measurements (mm), with the fix-ups of `_measured.py`. The camera (position,
  direction, up, 39.3077 degrees) becomes a `to_world` with Mitsuba's `look_at`; the film is
  the recommended 512 x 512 with the same Gaussian filter as the other box.
"""

import dataclasses
from importlib import resources
from pathlib import Path

from ._description import SceneDescription, read_scene_text
from ._json import load_json
from ._mitsuba_xml import load_mitsuba_xml

__all__ = ["BUILTIN_SCENES", "load_scene"]

BUILTIN_SCENES = {
    "cornell-box": "cornell_box.json",
    "cornell-box-measured": "cornell_box_measured.json",
}


def load_scene(name_or_path, *, params: dict | None = None) -> SceneDescription:
    """Load a built-in scene by name, or a scene file by path.

    **Arguments:**

    - `name_or_path`: `"cornell-box"` or `"cornell-box-measured"` (built-ins, see the module
        docstring of `radiometria.render._scene`), or a path to a `.json` scene (the schema of
        the built-in files) or a Mitsuba 3 `.xml` scene (the subset of `load_mitsuba_xml`).
        [name or path]
    - `params`: for `.xml` files, values for `$name` substitutions (override `<default>`).

    **Returns:**

    A `SceneDescription`.

    **Raises:**

    `FileNotFoundError` for a missing file; `SceneError` (a `ValueError`) naming the file and
    the line (XML, malformed JSON) or the field (JSON) for an invalid one; `ValueError`
    listing the built-in names for an unknown name without a file suffix.

    !!! note "Thesis"
        Ch. 8 (scenes for light transport); the Cornell box of `Goral1984`, as built by
        Mitsuba 3 (`Jakob2022`).
    """
    if isinstance(name_or_path, str) and name_or_path in BUILTIN_SCENES:
        fname = BUILTIN_SCENES[name_or_path]
        text = resources.files("radiometria.render").joinpath("data", fname).read_text("utf-8")
        scene = load_json(text, fname, measured_fixups=name_or_path == "cornell-box-measured")
        return dataclasses.replace(scene, source=name_or_path)
    path = Path(name_or_path)
    suffix = path.suffix.lower()
    if suffix == ".json":
        return load_json(read_scene_text(path), str(path))
    if suffix == ".xml":
        return load_mitsuba_xml(path, params=params)
    raise ValueError(
        f"Unknown scene {str(name_or_path)!r}: expected a built-in name "
        f"({', '.join(map(repr, BUILTIN_SCENES))}) or a path ending in .json or .xml."
    )
