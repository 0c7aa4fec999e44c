"""fit_pantograph: a chain's parameters recovered from its own FRF with measurement noise added,
and bad input named."""
import os
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
import yaml

from catenary_sim.pantograph_fit import chain_receptance, fit_chain, read_frf_csv

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FIT_CLI = os.path.join(ROOT, "scripts", "fit_pantograph")

# The paper's two-mass pantograph (config/calpe_example.yaml) and a three-mass chain like the
# reference one (config/reference_55m.yaml) with a damper at every stage.
CHAINS = [
    ([7.2, 15.0], [4200.0, 50.0], [10.0, 100.0]),
    ([7.5, 9.0, 6.0], [7000.0, 15500.0, 160.0], [20.0, 30.0, 100.0]),
]


def noisy_frf(chain, sigma, seed, n=40):
    f = np.geomspace(0.5, 20.0, n)
    rng = np.random.default_rng(seed)
    h = chain_receptance(f, *chain)
    # A laboratory FRF's error: relative, complex, independent per frequency (sigma per part).
    return f, h * (1.0 + sigma * (rng.standard_normal(n) + 1j * rng.standard_normal(n)))


@pytest.mark.parametrize("chain", CHAINS, ids=["two_masses", "three_masses"])
def test_fit_recovers_known_parameters_from_a_noisy_frf(chain):
    sigma = 0.01
    f, h = noisy_frf(chain, sigma, seed=7)
    fit = fit_chain(f, h, masses=len(chain[0]))
    # The residual is the noise: rms sigma sqrt(2) (two parts); with 2 x 40 values its sample rms
    # is within 10 % of that at one standard deviation (1 / sqrt(2 * 80)): 30 % is three.
    assert fit.residual_rms == pytest.approx(sigma * np.sqrt(2), rel=0.3)
    for name, truth in zip(("masses", "stiffness", "damping"), chain):
        got, std = getattr(fit, name), fit.std[name]
        # Each parameter within 4 standard deviations of the fit's covariance (a 6e-5 chance per
        # parameter for a normal error), and that deviation is small enough to mean something:
        # masses and springs to 10 % (the lower frame masses of three: about 5 %); dampers to 50 % (the three-mass chain's middle damper acts
        # on the relative motion of the two frame masses, which the head barely sees: 1 % noise
        # leaves it known to about a third).
        assert np.all(np.abs(got - truth) < 4 * std), (name, got, truth, std)
        assert np.all(std < (0.5 if name == "damping" else 0.1) * np.asarray(truth)), (name, std)


def test_noise_free_fit_is_exact():
    # Without noise the least squares reach the parameters to the solver's tolerance.
    f, h = noisy_frf(CHAINS[0], 0.0, seed=0)
    fit = fit_chain(f, h, masses=2)
    for got, truth in zip((fit.masses, fit.stiffness, fit.damping), CHAINS[0]):
        np.testing.assert_allclose(got, truth, rtol=1e-5)


def test_cli_writes_a_scene_snippet_and_the_residual(tmp_path):
    f, h = noisy_frf(CHAINS[0], 0.005, seed=3)
    csv = tmp_path / "frf.csv"
    pd.DataFrame({"frequency_hz": f, "receptance_re_m_per_n": h.real, "receptance_im_m_per_n": h.imag}).to_csv(csv, index=False)
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, FIT_CLI, str(csv), "--masses", "2", "--out", str(out), "--static-uplift", "120"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    snippet = yaml.safe_load((out / "pantograph_fit.yaml").read_text())
    p = snippet["pantographs"][0]
    np.testing.assert_allclose(p["masses"], CHAINS[0][0], rtol=0.05)
    assert p["static_uplift"] == 120
    table = pd.read_csv(out / "fit_residual.csv")
    assert len(table) == len(f) and table["relative_residual"].max() < 0.05


def test_bad_input_is_named(tmp_path):
    f, h = noisy_frf(CHAINS[0], 0.0, seed=0)
    with pytest.raises(ValueError, match="masses = 4"):
        fit_chain(f, h, masses=4)
    with pytest.raises(ValueError, match="at least 7"):
        fit_chain(f[:5], h[:5], masses=2)
    bad = tmp_path / "bad.csv"
    bad.write_text("freq,x\n1,2\n")
    with pytest.raises(ValueError, match="frequency_hz"):
        read_frf_csv(bad)
    r = subprocess.run([sys.executable, FIT_CLI, str(bad), "--out", str(tmp_path / "o")], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode != 0 and "frequency_hz" in r.stderr
    assert not (tmp_path / "o" / "pantograph_fit.yaml").exists()


def test_heads_on_a_frame_recovered_from_the_simulated_rig(tmp_path):
    # End to end on the core's own two-head pantograph (config/reference_55m_two_heads.yaml: two
    # heads of 3.75 kg on 3500 N/m and 10 N s/m each, on a frame of 9 and 6 kg): pantograph_frf
    # measures it on the simulated rig (stepped sines, force from the contact: within 0.2 % of the
    # lumped tree's analytic FRF), and fit_pantograph --heads 2 writes the frame and the two heads.
    # Heads driven together move as one mass 2 m on 2 k and 2 c: the FRF fixes those sums and the
    # snippet shares them out. The rig's 0.2 % error moves the fitted values by about as much:
    # 1 % for masses and springs, 2 % for the head dampers (a 20 N s/m damper in a 0.5-20 Hz FRF),
    # and the undamped upper frame spring fits below 1 N s/m (1 N s/m would shift the 9 kg mode's
    # peak by more than the rig's error).
    frf_bin = os.path.join(os.environ.get("CATENARY_SIM_DEVEL_LIB", os.path.join(ROOT, ".ws/devel/lib/catenary_sim")),
                           "pantograph_frf")
    scene = os.path.join(ROOT, "config", "reference_55m_two_heads.yaml")
    r = subprocess.run([frf_bin, scene, "--pantograph", "two_heads", "--out", str(tmp_path / "frf"), "--points", "16"],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    out = tmp_path / "fit"
    r = subprocess.run([sys.executable, FIT_CLI, str(tmp_path / "frf" / "frf.csv"), "--masses", "3", "--heads", "2",
                        "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    p = yaml.safe_load((out / "pantograph_fit.yaml").read_text())["pantographs"][0]
    np.testing.assert_allclose(p["masses"], [9.0, 6.0], rtol=0.01)
    np.testing.assert_allclose(p["stiffness"], [15500.0, 160.0], rtol=0.01)
    assert p["damping"][0] < 1.0 and p["damping"][1] == pytest.approx(100.0, rel=0.02)
    assert len(p["heads"]) == 2
    for h in p["heads"]:
        assert h["mass"] == pytest.approx(3.75, rel=0.01)
        assert h["stiffness"] == pytest.approx(3500.0, rel=0.01)
        assert h["damping"] == pytest.approx(10.0, rel=0.02)
    # The snippet is a pantograph the core takes: the two-head scene with it in place builds.
    import catenary_sim as cs
    with open(scene) as f:
        d = yaml.safe_load(f)
    d["pantographs"] = [p]
    cs.Simulation(d)


def test_heads_need_a_frame_below_them():
    f, h = noisy_frf(CHAINS[0], 0.0, seed=0)
    fit = fit_chain(f, h, masses=2)
    from catenary_sim.pantograph_fit import scene_snippet
    with pytest.raises(ValueError, match="heads = 0.5"):
        scene_snippet(fit, heads=0.5)


def write_frf(path, f, h):
    pd.DataFrame({"frequency_hz": f, "receptance_re_m_per_n": h.real, "receptance_im_m_per_n": h.imag}).to_csv(
        path, index=False)
    return str(path)


@pytest.mark.parametrize("name", ['a: "b', "it's", "x # y", "- z", "{q}", "naïve: [1]"])
def test_snippet_reads_back_for_any_name(tmp_path, name):
    # The snippet is YAML written by a YAML library: a name with a quote, a colon, a '#' or a
    # flow character reads back as given (pasted into text, it broke the file).
    f, h = noisy_frf(CHAINS[0], 0.0, seed=0)
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, FIT_CLI, write_frf(tmp_path / "frf.csv", f, h), "--out", str(out), "--name", name],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    p = yaml.safe_load((out / "pantograph_fit.yaml").read_text(encoding="utf-8"))["pantographs"][0]
    assert p["name"] == name
    np.testing.assert_allclose(p["masses"], CHAINS[0][0], rtol=1e-5)


def test_a_nan_row_is_refused_by_row(tmp_path):
    f, h = noisy_frf(CHAINS[0], 0.0, seed=0)
    h[7] = complex(np.nan, h[7].imag)
    with pytest.raises(ValueError, match=r"data row 8 .*receptance_re_m_per_n"):
        read_frf_csv(write_frf(tmp_path / "frf.csv", f, h))


def test_rows_at_one_frequency_are_too_few(tmp_path):
    # 12 rows at one frequency fix one complex value, not 6 parameters: refused (a "fit" with
    # std 0 before).
    f, h = noisy_frf(CHAINS[0], 0.0, seed=0)
    with pytest.raises(ValueError, match="1 distinct frequency .*12 rows.*at least 7 distinct"):
        fit_chain(np.full(12, f[3]), np.full(12, h[3]), masses=2)


def test_a_huge_frf_is_refused_not_left_to_run(tmp_path):
    # 240,000 rows ran for hours; refused at once with the bound.
    f = np.geomspace(0.5, 20.0, 240_000)
    h = chain_receptance(f, *CHAINS[0])
    r = subprocess.run([sys.executable, FIT_CLI, write_frf(tmp_path / "frf.csv", f, h), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "at most 20000" in r.stderr, r.stderr


def test_a_damper_the_frf_cannot_see_is_not_given_a_deviation(tmp_path):
    # A chain without a roof damper: the fit drives that damper towards 0, where the FRF no longer
    # depends on it, and the pseudo-inverse gave it a "std" of 1e-25 on a value of 1e-13. It is
    # said to be not identifiable; the others, which the FRF fixes, keep their deviations.
    chain = ([7.2, 15.0], [4200.0, 50.0], [10.0, 0.0])
    f, h = noisy_frf(chain, 0.0, seed=0)
    fit = fit_chain(f, h, masses=2)
    assert list(fit.identifiable["damping"]) == [True, False]
    assert fit.identifiable["masses"].all() and fit.identifiable["stiffness"].all()
    r = subprocess.run([sys.executable, FIT_CLI, write_frf(tmp_path / "frf.csv", f, h), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    line = [x for x in r.stdout.splitlines() if x.startswith("damping:")][0]
    first, second = line.split(":", 1)[1].split(",")
    assert "+-" in first and "not identifiable" in second and "+-" not in second
    assert "not identifiable from this FRF" in (tmp_path / "o" / "pantograph_fit.yaml").read_text()


def test_pantograph_frf_refuses_a_step_that_would_run_for_hours(tmp_path):
    # --dt 1e-7 is in the allowed range but takes about 3e10 steps of the rig (hours): refused at
    # once, naming --dt and the smallest step the step budget allows; a run within it prints its
    # progress.
    frf_bin = os.path.join(os.environ.get("CATENARY_SIM_DEVEL_LIB", os.path.join(ROOT, ".ws/devel/lib/catenary_sim")),
                           "pantograph_frf")
    scene = os.path.join(ROOT, "config", "reference_55m.yaml")
    r = subprocess.run([frf_bin, scene, "--pantograph", "leading", "--out", str(tmp_path / "frf"), "--dt", "1e-7",
                        "--no-plot"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2, r.stderr
    assert "--dt 1e-07" in r.stderr and "--max-steps" in r.stderr and "allowed: --dt >=" in r.stderr
    smallest = float(r.stderr.split("allowed: --dt >=")[1].split()[0])
    assert 1e-7 < smallest < 1e-4
    assert not os.path.exists(tmp_path / "frf" / "frf.csv")
    # With a budget below the default run's steps the default dt is refused too: the bound is the
    # budget, not a fixed dt.
    r = subprocess.run([frf_bin, scene, "--pantograph", "leading", "--out", str(tmp_path / "frf"), "--max-steps", "1000",
                        "--no-plot"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "--max-steps 1000" in r.stderr, r.stderr
