"""`radiometria lut build` / `lut check`."""

import pytest

import radiometria.upsampling as up
from radiometria.cli import main


@pytest.mark.slow
def test_lut_build_and_check(tmp_path, capsys):
    out = tmp_path / "t.coeff"
    assert main(["lut", "build", "--space", "sRGB", "--res", "6", "--out", str(out)]) == 0
    lut = up.load_lut(out)
    assert lut.resolution == 6 and lut.colourspace == "sRGB"
    assert main(["lut", "check", str(out), "--grid", "5", "--random", "100"]) == 0
    text = capsys.readouterr().out
    assert "rgb2spec-2026" in text and "CIEDE2000 mean" in text and "random 100" in text


def test_lut_cli_errors(tmp_path, capsys):
    assert (
        main(["lut", "build", "--space", "nope", "--res", "6", "--out", str(tmp_path / "a.npz")])
        == 2
    )
    assert main(["lut", "build", "--res", "1", "--out", str(tmp_path / "a.npz")]) == 2
    assert main(["lut", "build", "--res", "6", "--out", str(tmp_path / "a.txt")]) == 2
    assert main(["lut", "check", str(tmp_path / "absent.npz")]) == 2
    err = capsys.readouterr().err
    assert (
        "colourspace" in err
        and "--res" in err
        and ".npz or .coeff" in err
        and "no such file" in err
    )
