"""`import catenary_sim` (pybind11 module): physics through the skin, errors, views, commands.

Run by scripts/run_tests with Debian's pytest after sourcing the workspace."""
import json
import math
import os
import subprocess
import tempfile

import numpy as np
import pytest
import yaml

import catenary_sim as cs

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
REFERENCE = os.path.join(ROOT, "config", "reference_55m.yaml")


def single_wire(span=50.0, tension=20000.0, linear_mass=1.35, h=0.25, force=100.0):
    """One tensioned wire between two rigid supports and a force pressing it up at mid-span,
    standing still (a moving force at speed 0)."""
    return {
        "name": "single_wire",
        "line": {"span_length": span, "span_count": 1},
        "contact_wire": {"linear_mass": linear_mass, "bending_stiffness": 0.0, "tension": tension},
        "pantographs": [{"name": "force", "type": "moving_force", "static_uplift": force}],
        "train": {"speed": 0.0, "start": span / 2.0},
        "numerics": {"element_length": h},
        "output": {"analysis_spans": [0, 1]},
    }


def test_static_deflection_under_a_point_force_converges_to_the_tensioned_beam():
    # A simply supported beam in tension T with bending stiffness EI under a point force F at
    # mid-span rises F / (2 k T) (u - tanh u) there, k = sqrt(T / EI), u = k L / 2 (Timoshenko's
    # beam-column in tension). Hermite elements converge to it at about the fourth order in h
    # (measured: 2.6e-6 at 0.1 m, 1.8e-7 at 0.05 m): the error must fall below 1e-6 at 0.05 m and by
    # more than 8x when h halves (16x for the fourth order, with room for round-off).
    span, tension, force, ei = 50.0, 20000.0, 100.0, 195.0
    k = math.sqrt(tension / ei)
    u = k * span / 2.0
    exact = force / (2.0 * k * tension) * (u - math.tanh(u))
    errors = []
    for h in (0.1, 0.05):
        scene = single_wire(span, tension, force=force, h=h)
        scene["contact_wire"]["bending_stiffness"] = ei
        sim = cs.Simulation(scene)
        errors.append(abs(np.max(sim.displacements) - exact) / exact)
    assert errors[1] < 1e-6
    assert errors[0] / errors[1] > 8.0


def test_errors_name_the_field_the_value_and_what_is_allowed():
    with pytest.raises(cs.SceneError) as e:
        cs.Simulation(REFERENCE, overrides={"pantographs.0.static_uplift": -1})
    assert e.value.field == "pantographs[0].static_uplift"
    assert e.value.value == "-1"
    assert "[0, 2000]" in e.value.allowed
    with pytest.raises(cs.SceneError) as e:
        cs.Simulation(REFERENCE, overrides=["contact_wire.tensoin=1"])
    assert e.value.field == "contact_wire.tensoin"
    with pytest.raises(cs.SceneError) as e:
        cs.Simulation(REFERENCE, overrides=["name.foo=1"])
    assert e.value.field == "name.foo"
    with pytest.raises(cs.SceneError):
        cs.Simulation({"line": "not a map"})
    with pytest.raises(cs.SceneError):
        cs.Simulation(42)
    with pytest.raises(cs.SceneError):
        cs.Simulation(REFERENCE, sample_rate=float("nan"))
    with pytest.raises(ValueError, match="max_steps"):
        cs.Simulation(single_wire()).run()  # speed 0: would never end


def test_a_rejected_command_leaves_the_state_as_it_was():
    sim = cs.Simulation(REFERENCE)
    sim.step(10)
    speed, uplift = sim.speed, sim.pantograph_state()["uplift_N"]
    for bad in (-1.0, float("nan"), 1e9):
        with pytest.raises(ValueError):
            sim.set_speed(bad)
        with pytest.raises(ValueError):
            sim.set_uplift(bad)
    sim.step(10)
    assert sim.speed == speed
    assert sim.pantograph_state()["uplift_N"] == uplift


def test_views_follow_the_state_without_copies_and_are_read_only():
    sim = cs.Simulation(REFERENCE)
    u = sim.displacements
    assert u.shape == (sim.dofs,)
    assert not u.flags.writeable
    before = u.copy()
    sim.step(50)
    assert sim.steps == 50 and sim.time == pytest.approx(50 * sim.dt, rel=1e-12)
    assert not np.array_equal(u, before)  # the same view shows the new state
    f = sim.contact_forces
    assert f.shape == (1, 1) and f[0, 0] > 0.0
    assert sim.pantograph_state()["contact_force_N"] == pytest.approx(f.sum(), rel=1e-12)


def test_pantograph_state_gives_every_head():
    # config/reference_55m_two_heads.yaml: two heads at +-0.25 m, each with aero 0.002 N s^2/m^2.
    sim = cs.Simulation(os.path.join(ROOT, "config", "reference_55m_two_heads.yaml"))
    sim.step(200)
    st = sim.pantograph_state(0)
    assert len(st["head_heights_m"]) == 2 and len(st["head_contact_forces_N"]) == 2
    # The head height of old is the heads' mean; the heads' forces add up to the pantograph's.
    assert st["head_height_m"] == pytest.approx(sum(st["head_heights_m"]) / 2, rel=1e-15)
    assert sum(st["head_contact_forces_N"]) == pytest.approx(st["contact_force_N"], rel=1e-12)
    assert all(f >= 0.0 for f in st["head_contact_forces_N"]) and st["contact_force_N"] > 0.0
    assert st["head_heights_m"][0] != st["head_heights_m"][1]  # each on its own suspension
    v = 300.0 / 3.6  # the scene's speed
    assert st["head_aero_uplift_N"] == pytest.approx([0.002 * v * v] * 2, rel=1e-12)
    assert st["knee"] == "leading"
    # A chain is one head, its first mass.
    one = cs.Simulation(REFERENCE).pantograph_state(0)
    assert one["head_heights_m"] == [one["head_height_m"]]
    assert one["head_aero_uplift_N"] == [0.0]


def test_a_head_wind_adds_to_the_aerodynamic_uplift():
    # a v^2 is a still-air coefficient: a 15 m/s wind from ahead (direction 180 deg) makes the
    # pantograph's speed through the air v + 15 m/s (test_lateral: the momentum balance).
    sim = cs.Simulation(REFERENCE, overrides=["pantographs.0.aero_coefficient=0.01", "wind.speed=15",
                                              "wind.direction=180"])
    sim.step(10)
    st = sim.pantograph_state(0)
    v = 300.0 / 3.6
    assert st["head_wind_m_s"] == pytest.approx(15.0, abs=1e-12)
    assert st["aero_uplift_N"] == pytest.approx(0.01 * (v + 15.0) ** 2, rel=1e-12)
    calm = cs.Simulation(REFERENCE, overrides=["pantographs.0.aero_coefficient=0.01"]).pantograph_state(0)
    assert calm["head_wind_m_s"] == 0.0 and calm["aero_uplift_N"] == pytest.approx(0.01 * v * v, rel=1e-12)


def test_a_pass_from_python_equals_simulate_pass():
    # The module adds no physics: the same scene gives the same statistics, bit for bit, as the
    # offline runner (the same core and the same fixed dt; only the skin differs).
    stats, series = cs.run_pass(REFERENCE, overrides={"train.speed_kmh": 250})
    with tempfile.TemporaryDirectory() as d:
        binary = os.path.join(os.environ.get("CATENARY_SIM_DEVEL_LIB", os.path.join(ROOT, ".ws/devel/lib/catenary_sim")),
                              "simulate_pass")
        subprocess.run([binary, "--scene", REFERENCE, "--out", d, "--speed", "250", "--quiet"], check=True)
        with open(os.path.join(d, "stats.json")) as f:
            tool = json.load(f)
    for key in ("mean_force_N", "std_force_N", "max_force_N", "min_force_N", "contact_loss_percent"):
        assert stats["pantographs"][0][key] == tool["pantographs"][0][key], key
    assert stats["steps"] == tool["steps"]
    # The line's figures too (what a study reads as steady_arms.3.max_uplift_m and the like).
    for key in ("steady_arms", "droppers", "support_stations_m", "dropper_stations_m", "limits"):
        assert stats[key] == tool[key], key
    # The series at the scene's output.sample_rate (1000 Hz): one row per ms of the 7.9 s pass.
    assert series["time_s"].shape[0] == pytest.approx(stats["simulated_time_s"] * 1000.0, abs=2)
    assert np.all(np.isfinite(series["leading_force_N"]))


def test_a_dict_scene_equals_its_file():
    with open(REFERENCE) as f:
        scene = yaml.safe_load(f)
    a, _ = cs.run_pass(scene, sample_rate=0)
    b, _ = cs.run_pass(REFERENCE, sample_rate=0)
    assert a["pantographs"][0]["std_force_N"] == b["pantographs"][0]["std_force_N"]


def test_steady_arms_sit_at_the_supports_at_the_contact_wire_height():
    # The scene holds the contact wire at line.contact_wire_height at every support of a single
    # tension section (presag is at mid-span), one span_length apart: what plot_contact_force needs
    # to turn a recorded wire_shape into steady-arm uplift.
    with open(REFERENCE) as f:
        line = yaml.safe_load(f)["line"]
    arms = cs.Simulation(REFERENCE).steady_arms
    assert 1 <= len(arms) <= line["span_count"] + 1
    for a in arms:
        assert a["wire"] == "contact_wire"
        spans = a["station_m"] / line["span_length"]
        assert abs(spans - round(spans)) < 1e-9 and 0 <= round(spans) <= line["span_count"]
        assert a["design_height_m"] == pytest.approx(line["contact_wire_height"], abs=1e-9)
        assert a["wire_start_m"] == 0.0


def test_a_3d_pass_reports_the_contact_point_across_the_strip_as_simulate_pass_does():
    # Stagger +-0.3 m, no wind: the wire runs along the chords between the registrations, so the
    # contact point sweeps the strip from -0.3 to +0.3 m (within the beam's 1 mm rounding of each
    # kink, test_lateral's StaggerChordsUnderThePantograph) at the rate the chord slope and the
    # speed set: 0.6 m per 55 m span at 300 km/h = 0.909 m/s. The statistics are those of
    # simulate_pass (one writer, core/pass_files), and a 2-D scene has no lateral object.
    over = {"line.span_count": 6, "output.analysis_spans": [1, 5], "stagger.contact_wire": [0.3, -0.3],
            "train.speed_kmh": 300}
    stats, _ = cs.run_pass(REFERENCE, overrides=over)
    c = stats["lateral"]["contact_points"][0]
    assert c["max_m"] == pytest.approx(0.3, abs=1e-3)
    assert c["min_m"] == pytest.approx(-0.3, abs=1e-3)
    assert c["sweep_speed_mean_mps"] == pytest.approx(0.6 / 55.0 * 300 / 3.6, rel=0.01)
    assert stats["stopped_by_dewirement"] is False
    with tempfile.TemporaryDirectory() as d:
        binary = os.path.join(os.environ.get("CATENARY_SIM_DEVEL_LIB", os.path.join(ROOT, ".ws/devel/lib/catenary_sim")),
                              "simulate_pass")
        subprocess.run([binary, "--scene", REFERENCE, "--out", d, "--quiet"] +
                       [f"--set={k}={json.dumps(v).replace(' ', '')}" for k, v in over.items()], check=True)
        with open(os.path.join(d, "stats.json")) as f:
            tool = json.load(f)
        assert os.path.exists(os.path.join(d, "lateral.csv"))
    assert tool["lateral"]["contact_points"][0]["max_m"] == c["max_m"]
    assert "lateral" not in cs.run_pass(REFERENCE, overrides={"line.span_count": 4, "output.analysis_spans": [1, 3]})[0]
