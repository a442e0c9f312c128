"""colour-science emits ColourRuntimeWarning (not a ColourWarning subclass) when it aligns
spectral shapes, which the reference comparisons do on purpose."""

import pytest


def pytest_collection_modifyitems(items):
    for item in items:
        if "tests/colorimetry" in str(item.fspath).replace("\\", "/"):
            item.add_marker(
                pytest.mark.filterwarnings("ignore::colour.utilities.ColourRuntimeWarning")
            )
