"""The fault audit (qa.fault_audit, its cases qa.fault_cases, its planted files
qa.planted_files): its classifier on made-up process results, its case table, and a few
real cases run end to end through the command line."""

from __future__ import annotations

import pickle
from collections import Counter

import numpy as np
import pytest

from ffrmbs.errors import InputFileError
from mbs.results.checkpoint import read_checkpoint
from qa import fault_audit as fa
from qa import fault_cases as fc
from qa import planted_files as pf

LONG = "ffrmbs: error: x.toml: " + "y" * 300


def test_a_message_is_as_clear_wherever_the_audit_writes():
    """The length limit counts the message without the case directory's path (found at 302
    characters under a long ``--out``)."""
    deep = "/" + "d" * 120 + "/cases/unknown_body_key"
    stderr = f"ffrmbs: error: {deep}/scene.toml, line 4: unknown key 'bogus' in [[bodies]]; " + "k, " * 60 + "\n"
    assert len(stderr.strip()) > fa.MAX_MESSAGE
    assert fa.classify(2, stderr, ("bogus",), case_dir=deep)[0] == "clear"
    assert fa.classify(2, stderr, ("bogus",))[0] == "unclear"


@pytest.mark.parametrize("returncode, stderr, expect, timed_out, executed, outcome", [
    (2, "ffrmbs: error: /a/scene.toml, line 3: 'dt' must be > 0 [s]\n", ("dt",), False, False, "clear"),
    (2, "usage: ffrmbs run ...\nffrmbs run: error: argument --dt: expected one argument\n", ("--dt",), False, False,
     "clear"),                                                   # argparse's form
    (2, "ffrmbs: error: mesh size must be positive, not 0\n", ("--mesh-size",), False, False, "clear"),
    (2, "ffrmbs: error: Poisson's ratio must lie in (-1, 0.5)\n", ("poisson",), False, False, "clear"),
    (1, "Traceback (most recent call last):\n  File ...\nValueError: bad\n", ("x",), False, False, "traceback"),
    (2, "ffrmbs: error: x.inp: oops\nTraceback (most recent call last):\nffrmbs: error: x.inp\n", ("x.inp",), False,
     False, "traceback"),
    (2, "ffrmbs: error: x.inp: cannot read\nsecond line of the message\n", ("x.inp",), False, False, "unclear"),
    (2, LONG + "\n", ("x.toml",), False, False, "unclear"),          # too long
    (2, "ffrmbs: error: something is wrong\n", ("u0.dat",), False, False, "unclear"),   # names nothing
    (2, "error: u0.dat is bad\n", ("u0.dat",), False, False, "unclear"),                # not our prefix
    (2, "ffrmbs: error: simulation stopped: the mode must be finite\n", fc.E_KEY, False, False, "unclear"),
    (1, "", ("x",), False, False, "unclear"),
    (-9, "", ("x",), False, False, "unclear"),                                           # killed by a signal
    (0, "", ("x",), False, False, "silent"),
    (0, "some warning\n", ("x",), False, False, "silent"),
    (None, "meshing ...\n", ("x",), True, False, "hang"),
    (2, "ffrmbs: error: x.ckpt: not an ffrmbs checkpoint\n", ("ckpt",), False, True, "silent"),   # code ran anyway
])
def test_classify(returncode, stderr, expect, timed_out, executed, outcome):
    got, message = fa.classify(returncode, stderr, expect, timed_out, executed)
    assert got == outcome
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    assert message.endswith(lines[-1] if lines else "")
    assert message.startswith("EXECUTED") == executed


def test_the_case_table_covers_every_kind_with_at_least_102_cases():
    cases = fc.all_cases()        # builds every scene text: each edit matched BASE_SCENE exactly once
    assert len(cases) >= 102
    assert len({c.name for c in cases}) == len(cases)
    kinds = Counter(c.kind for c in cases)
    assert set(kinds) == set(fc.KINDS) and min(kinds.values()) >= 10
    assert all(c.expect for c in cases), "every bad input names what a clear message must mention"
    assert sum(c.marker is not None for c in cases) == 3      # the planted pickles: bare, old header, in an .npz


@pytest.mark.parametrize("name, source, options, expect", fc.MESH_OPTIONS, ids=[c[0] for c in fc.MESH_OPTIONS])
def test_bad_preprocess_options_reach_the_command(name, source, options, expect):
    """The bad value of an option appended to a valid command is the one the parser keeps (a
    repeated option keeps its last value; nothing after it overrides it)."""
    from ffrmbs_app.cli import build_parser

    argv = [a.format(case="/c", shared="/s") for a in fc.all_cases_by_name()[f"mesh_{name}"].argv]
    args = build_parser().parse_args(argv)
    for flag, value in zip(options[::2], options[1::2]):
        got = getattr(args, flag[2:].replace("-", "_"))
        want = type(got)(value.format(case="/c", shared="/s"))
        assert got == want or (got != got and want != want), (flag, got, value)


def test_the_planted_pickle_runs_its_command_when_loaded(tmp_path):
    """The planted checkpoint is a real threat: unpickling it creates the marker."""
    ckpt = tmp_path / "x.h5.ckpt"
    pf.planted_pickle(pf.PICKLED_HEADER, "EXECUTED")(ckpt, tmp_path)
    data = ckpt.read_bytes()
    assert data.startswith(pf.PICKLED_HEADER)
    assert not (tmp_path / "EXECUTED").exists()
    pickle.loads(data[len(pf.PICKLED_HEADER):])
    assert (tmp_path / "EXECUTED").exists()


def test_the_planted_object_array_runs_its_command_when_loaded_with_pickles_allowed(tmp_path):
    """The planted .npz is a real threat to a reader that allows pickles."""
    ckpt = tmp_path / "x.h5.ckpt"
    pf.planted_object_array("EXECUTED")(ckpt, tmp_path)
    with np.load(ckpt, allow_pickle=True) as npz:
        npz["plant"]
    assert (tmp_path / "EXECUTED").exists()


@pytest.mark.parametrize("name, refusal", [
    ("resume_planted_pickle", "not an ffrmbs checkpoint, or damaged"),
    ("resume_planted_pickle_with_header", "a pickled checkpoint of an older ffrmbs (ffrmbs-checkpoint-2): refused"),
    ("resume_planted_object_array", "not an ffrmbs checkpoint, or damaged (ValueError: 'Object arrays cannot"),
    ("resume_truncated_checkpoint", "not an ffrmbs checkpoint, or damaged"),
])
def test_the_planted_checkpoints_are_refused_unread(tmp_path, name, refusal):
    """Each planted or damaged checkpoint of the audit is refused by read_checkpoint, and
    nothing it holds runs."""
    path, make = [f for f in _case(f"run_{name}").files if f[0] == fc.CKPT][0]
    ckpt = tmp_path / "x.h5.ckpt"
    make(ckpt, tmp_path)
    with pytest.raises(InputFileError) as err:
        read_checkpoint(ckpt)
    assert refusal in str(err.value)
    assert not (tmp_path / "EXECUTED").exists()


@pytest.fixture(scope="module")
def audit_root(tmp_path_factory):
    root = tmp_path_factory.mktemp("audit")
    (root / "shared").mkdir()
    fc.build_shared(root / "shared")
    return root


def _case(name):
    return fc.all_cases_by_name()[name]


@pytest.mark.parametrize("name, fragment", [
    ("info_u0_nan", "u0.dat"),                  # a NaN in the node positions, read by ffrmbs info
    ("syntax_table", "scene.toml, line"),       # a TOML syntax error in a scene file
    ("mesh_box_letters", "box:a,b,c"),          # ffrmbs preprocess box:a,b,c
])
def test_real_cases_with_clear_errors(audit_root, name, fragment):
    result = fa.run_case(_case(name), audit_root)
    assert result.outcome == "clear", result.message
    assert result.returncode == 2 and fragment in result.message


def test_a_valid_input_counts_as_silent_and_planted_code_as_executed(audit_root):
    """Exit status 0 on a (here valid) input is 'silent'; a marker present afterwards is flagged
    EXECUTED whatever the exit status."""
    valid = fc.Case("valid_body", "body", ("info", "{shared}/body.h5"), ("body.h5",))
    assert fa.run_case(valid, audit_root).outcome == "silent"
    marked = fc.Case("marked", "body", ("info", "{case}/missing.h5"), ("missing.h5",),
                     files=(("EXECUTED", pf.text("")),), marker="EXECUTED")
    result = fa.run_case(marked, audit_root)
    assert result.outcome == "silent" and result.executed and result.message.startswith("EXECUTED")
    assert result.returncode == 2                    # the error was clear, yet code ran


def test_markdown_and_summary_give_the_counts():
    doc = {"counts": {"clear": 2, "traceback": 1, "unclear": 0, "silent": 1, "hang": 0}, "tried": 4,
           "by_kind": {"scene": {"clear": 2, "silent": 1}, "run": {"traceback": 1}}, "executed": ["run_x"],
           "controls": [{"case": "control_scene", "outcome": "ok"}],
           "limits": {"timeout_s": 60.0, "memory_bytes": 4 << 30},
           "cases": [{"case": "a|b", "kind": "scene", "outcome": "clear", "returncode": 2, "seconds": 0.5,
                      "message": "ffrmbs: error: x"}]}
    line = fa.summary_line(doc)
    assert line.startswith("bad inputs tried 4: clear 2, traceback 1, unclear 0, silent 1, hang 0")
    assert "EXECUTED planted code: run_x" in line
    md = fa.markdown(doc)
    assert "| scene | 2 | 0 | 0 | 1 | 0 |" in md and "| run | 0 | 1 | 0 | 0 | 0 |" in md
    assert "| a\\|b | scene | clear | 2 | 0.5 | ffrmbs: error: x |" in md
    assert "1 of 1 ran cleanly." in md
