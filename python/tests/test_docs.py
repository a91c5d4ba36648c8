"""The Python example of doc/user_guide.md runs, on a scan of the tests' own."""

import os
import re

from conftest import ROOT


def test_user_guide_example_runs(room_scans, tmp_path, capsys):
    text = open(os.path.join(ROOT, "doc", "user_guide.md")).read()
    example = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    example = example.replace('"kinect_capture0001.pcd"', repr(room_scans[0][0]))
    example = example.replace('"map.ot"', repr(str(tmp_path / "map.ot")))
    exec(compile(example, "user_guide.md", "exec"), {})
    printed = capsys.readouterr().out.split("\n")
    assert printed[-2] == "0"  # psi of the map and its saved copy
    assert (tmp_path / "map.ot").is_file()
