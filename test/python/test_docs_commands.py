"""Every command that README.md and docs/ show runs as written (scripts/check_docs_commands in its
--quick mode: launch files loaded with their arguments rather than started, tools stopped once they
have accepted their input), and the checker itself tells a runnable command from a broken one."""
import os
import re
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CHECKER = os.path.join(ROOT, "scripts", "check_docs_commands")
HAVE_BUILD = os.path.isdir(os.path.join(ROOT, ".ws", "devel", "lib", "catenary_sim"))

needs_build = pytest.mark.skipif(not HAVE_BUILD, reason="no build in .ws/ (scripts/build all)")

PAGE = """# A page

    .ws/devel/lib/catenary_sim/simulate_pass --help
    simulate_pass --help

Text between blocks.

<!-- docs-check: skip it needs a real rig -->

    roslaunch catenary_sim hil.launch virtual_rig:=false

Another block.

    roslaunch catenary_sim pass.launch no_such_argument:=1
    roslaunch catenary_sim pass.launch scene:=... speed_kmh:=250
    roslaunch catenary_sim pass.launch speed_kmh:=250 at_end:=loop

    --scene FILE      a flag table, not a command
"""


def run_checker(*args, timeout):
    proc = subprocess.Popen(["/usr/bin/python3", CHECKER] + list(args), cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.terminate()   # the checker stops the commands it started on SIGTERM
        out, err = proc.communicate()
        pytest.fail("check_docs_commands took more than %d s:\n%s" % (timeout, out[-6000:]))
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def test_commands_are_found_in_code_blocks_with_their_lines(tmp_path):
    page = tmp_path / "page.md"
    page.write_text(PAGE)
    r = run_checker("--list", str(page), timeout=60)
    assert r.returncode == 0, r.stdout + r.stderr
    lines = [int(m) for m in re.findall(r"page\.md:(\d+)", r.stdout)]
    assert lines == [3, 4, 10, 14, 15, 16]
    assert "[skip it needs a real rig]" in r.stdout
    assert "a flag table" not in r.stdout


@needs_build
def test_checker_fails_a_bare_tool_an_undeclared_argument_and_a_placeholder(tmp_path):
    page = tmp_path / "page.md"
    page.write_text(PAGE)
    r = run_checker("--quick", str(page), timeout=300)
    out = r.stdout
    status = dict((int(n), s) for s, n in re.findall(r"^(PASS|FAIL|SKIP) \S*page\.md:(\d+)",
                                                     out, re.MULTILINE))
    assert status == {3: "PASS", 4: "FAIL", 10: "SKIP", 14: "FAIL", 15: "FAIL", 16: "PASS"}, out
    assert "command not found" in out
    assert "undeclared launch argument(s): no_such_argument" in out
    assert "no such file: scene:=..." in out
    assert "3 passed" not in out and "2 passed, 3 failed, 1 skipped" in out
    assert r.returncode == 1


@needs_build
def test_every_command_in_readme_and_docs_runs():
    # Bounded: each tool runs at most --quick-limit seconds, launch files are only loaded.
    r = run_checker("--quick", timeout=900)
    summary = r.stdout[r.stdout.rfind("=" * 20):]
    assert r.returncode == 0, summary + "\n" + r.stdout[-6000:] + r.stderr[-2000:]
