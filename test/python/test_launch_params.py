"""A launch leaves no parameter of an earlier launch behind on the same master: every node's private
parameters are those its own launch gives, whatever an earlier launch with other arguments set
(a parameter set only under `if=` stayed, e.g. a UDP transport or a speed). The parameter server
is played as roslaunch plays it: the `clear_params` namespaces deleted, then every parameter set."""
import os

import pytest

roslaunch = pytest.importorskip("roslaunch")
import roslaunch.config  # noqa: E402
import roslaunch.xmlloader  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def load(launch, args):
    config = roslaunch.config.ROSLaunchConfig()
    roslaunch.xmlloader.XmlLoader().load(os.path.join(ROOT, "launch", launch), config, argv=list(args),
                                         verbose=False)
    return config


def launch_on(server, config):
    for ns in config.clear_params:
        for key in [k for k in server if k.startswith(ns)]:
            del server[key]
    for key, p in config.params.items():
        server[key] = p.value
    return server


def private(server, config):
    """The parameters under the private namespaces of the launch's nodes."""
    namespaces = [(n.namespace + n.name).rstrip("/") + "/" for n in config.nodes]
    return {k: v for k, v in server.items() if any(k.startswith(ns) for ns in namespaces)}


@pytest.mark.parametrize("launch,first,second", [
    ("hil.launch",
     ["udp:=true", "speed_kmh:=100", "stats_file:=/tmp/s.json", "report_file:=/tmp/r.json", "cpus:=1",
      "udp_rig:=127.0.0.1:47801", "udp_allow:=127.0.0.1"],
     []),
    ("hil.launch", ["udp:=true", "inprocess:=true"], ["inprocess:=true"]),
    ("pass.launch",
     ["speed_kmh:=100", "stats_file:=/tmp/s.json", "report_file:=/tmp/r.html", "plot:=true", "plot_png:=/tmp/p.png"],
     ["plot:=true"]),
    ("replay.launch", ["bag:=/tmp/x.bag", "plot:=true", "plot_png:=/tmp/p.png"], ["bag:=/tmp/x.bag", "plot:=true"]),
])
def test_a_second_launch_keeps_nothing_of_the_first(launch, first, second):
    after_first = launch_on({}, load(launch, first))
    config = load(launch, second)
    fresh = private(launch_on({}, config), config)
    assert fresh, "no node parameters to compare"
    assert private(launch_on(after_first, config), config) == fresh
