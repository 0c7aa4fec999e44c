"""The rviz configurations load (rviz falls back to an empty default, silently, on a YAML error:
no markers shown) and hold the views the user guide names."""
import os

import pytest
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.mark.parametrize("name,current,saved", [
    ("catenary_sim.rviz", "rviz/Orbit", "rviz/TopDownOrtho"),
    ("catenary_sim_top.rviz", "rviz/TopDownOrtho", "rviz/Orbit"),
    ("replay.rviz", None, None),
])
def test_rviz_config_parses_and_has_its_views(name, current, saved):
    with open(os.path.join(ROOT, "config", name)) as f:
        cfg = yaml.safe_load(f)
    manager = cfg["Visualization Manager"]
    topics = [d.get("Marker Topic") for d in manager["Displays"]]
    assert "/markers" in topics
    views = manager["Views"]
    if current:
        assert views["Current"]["Class"] == current
        assert views["Current"]["Target Frame"] == "train_view"
        assert [v["Class"] for v in views["Saved"]] == [saved]
        assert all(v["Target Frame"] == "train_view" for v in views["Saved"])
