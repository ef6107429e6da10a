"""scripts/result_fingerprint.py: the same run gives the same fingerprint, and one changed bit changes it."""
from __future__ import annotations

from pa10_dnbs.run_settings import build_settings
import dataclasses

import numpy as np
import pytest
from script_module import load_script

fp = load_script("result_fingerprint")


def test_digest_sees_one_ulp_the_order_and_the_shape():
    a = np.linspace(0.0, 1.0, 12)
    b = a.copy()
    b[5] = np.nextafter(b[5], 2.0)
    assert fp.digest([a]) == fp.digest([a.copy()])
    assert fp.digest([a]) != fp.digest([b])
    assert fp.digest([a, b]) != fp.digest([b, a])
    assert fp.digest([a]) != fp.digest([a.reshape(3, 4)])


def test_banks_are_deterministic_and_sensitive_to_one_ulp_of_a_parameter():
    from pa10_dnbs.config import default_config_path
    from pa10_dnbs.controller_factory import dnbs_params

    p = dataclasses.replace(dnbs_params(build_settings(default_config_path())), remedies=fp.ALL_REMEDIES)
    once = fp.digest(fp.banks(p, steps=60))
    assert fp.digest(fp.banks(p, steps=60)) == once
    scale = p.torque_net.output_scale.copy()
    scale[4] = np.nextafter(scale[4], 100.0)  # one joint's U [N m], one ulp up
    nudged = dataclasses.replace(p, torque_net=dataclasses.replace(p.torque_net, output_scale=scale))
    assert fp.digest(fp.banks(nudged, steps=60)) != once


def test_the_bank_of_seven_equals_the_banks_of_one_in_the_scenarios():
    from pa10_dnbs.config import default_config_path
    from pa10_dnbs.controller_factory import dnbs_params

    p = dataclasses.replace(dnbs_params(build_settings(default_config_path())), remedies=fp.ALL_REMEDIES)
    rows7, rows1, *_ = fp.banks(p, steps=250)  # past the EKF reset at step 211
    assert rows7[:, :7].tobytes() == rows1.tobytes()


def test_the_compiled_kernel_gives_the_banks_fingerprint():
    """``--kernel c``: the bank scenarios (every remedy, untrusted rows, saturation, an EKF reset at step 211)
    have the numpy reference's fingerprint."""
    from pa10_dnbs.config import default_config_path
    from pa10_dnbs.controller_factory import dnbs_params

    p = dataclasses.replace(dnbs_params(build_settings(default_config_path())), remedies=fp.ALL_REMEDIES)
    assert fp.digest(fp.banks(p, steps=250, kernel="c")) == fp.digest(fp.banks(p, steps=250))


def test_save_keeps_the_platform_and_compare_says_when_it_differs(tmp_path, monkeypatch, capsys):
    """The closed-loop scenarios' bits differ between OpenBLAS kernels (pa10_dnbs/numeric_platform.py): a
    comparison with a file saved on another platform says so, beside its verdict."""
    import json
    import sys

    monkeypatch.setattr(fp, "fingerprints", lambda kernel: {"default": "ab", "bare": "cd"})
    saved = tmp_path / "before.json"
    monkeypatch.setattr(sys, "argv", ["result_fingerprint.py", "--kernel", "numpy", "--save", str(saved)])
    assert fp.main() == 0
    data = json.loads(saved.read_text())
    assert data["platform"] == fp.platform_line(fp.numeric_platform()) and data["default"] == "ab"
    monkeypatch.setattr(sys, "argv", ["result_fingerprint.py", "--kernel", "numpy", "--compare", str(saved)])
    capsys.readouterr()
    assert fp.main() == 0
    assert "another numeric platform" not in capsys.readouterr().out
    saved.write_text(json.dumps(dict(data, platform="OpenBLAS 0.3.31, Haswell kernels; numpy 2.4.6, SIMD X86_V3",
                                     bare="ce")))
    assert fp.main() == 1
    out = capsys.readouterr().out
    assert "note: saved on another numeric platform (OpenBLAS 0.3.31, Haswell kernels" in out
    assert out.rstrip().endswith("2 scenarios, 1 differ: bare")


def test_a_save_whose_write_fails_is_one_line_and_keeps_the_old_file(tmp_path, monkeypatch, capsys):
    """A --save whose write fails (a full disk: ENOSPC after part of the file) was an OSError traceback that left
    the file cut short; now one line, exit 1, and the file as it was."""
    import errno
    import os
    import sys
    from pathlib import Path

    monkeypatch.setattr(fp, "fingerprints", lambda kernel: {"default": "ab", "bare": "cd"})
    saved = tmp_path / "before.json"
    saved.write_text("the fingerprints of before\n")
    write_text = Path.write_text

    def full_disk(self, data, *args, **kwargs):
        write_text(self, data[:5])
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(self))

    monkeypatch.setattr(Path, "write_text", full_disk)
    monkeypatch.setattr(sys, "argv", ["result_fingerprint.py", "--kernel", "numpy", "--save", str(saved)])
    assert fp.main() == 1
    monkeypatch.undo()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--save" in err and os.strerror(errno.ENOSPC) in err, err
    assert saved.read_text() == "the fingerprints of before\n" and list(tmp_path.iterdir()) == [saved]


@pytest.mark.parametrize("when", ["loading", "running"])
def test_ctrl_c_is_one_line_exit_130_and_nothing_saved(when, tmp_path):
    """A Ctrl-C (SIGINT to the process group, as a terminal sends it) while numpy and the simulator load or while
    the scenarios run: one line, exit 130, no file; it was a KeyboardInterrupt traceback."""
    import os
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    saved = tmp_path / "x.json"
    proc = subprocess.Popen([sys.executable, str(Path(fp.__file__)), "--save", str(saved)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            env=dict(os.environ, PYTHONUNBUFFERED="1"))
    try:
        if when == "loading":   # numpy mapped: the script runs, the simulator is still to load
            t0 = time.monotonic()
            while "numpy" not in Path(f"/proc/{proc.pid}/maps").read_text():
                assert proc.poll() is None and time.monotonic() - t0 < 30, proc.communicate()
                time.sleep(0.002)
        else:
            assert proc.stdout.readline().startswith("numeric platform:")
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert proc.returncode == 130 and err == ("result_fingerprint: interrupted before the fingerprints were done: "
                                              "nothing saved or compared\n"), (proc.returncode, err)
    assert list(tmp_path.iterdir()) == []
