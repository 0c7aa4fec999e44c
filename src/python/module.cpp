// catenary_sim._core: the core for Python (pybind11), a thin skin over Simulation like the ROS
// layer is: no physics here. The Python package (python/catenary_sim/__init__.py) adds scenes from
// dicts and the SceneError exception with the field, the value and what is allowed.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "../core/util/format.hpp"

#include "catenary_sim/core/output/output_files.hpp"
#include "catenary_sim/core/output/pass_files.hpp"
#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "catenary_sim/core/output/zero_phase_filter.hpp"

namespace py = pybind11;
using namespace catenary_sim;

namespace {

// A read-only numpy view of a state vector, alive as long as the simulation object.
py::array_t<double> view(const double* data, std::size_t n, py::handle owner) {
  py::array_t<double> a({n}, {sizeof(double)}, data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

// A pass of a scene with its recorder: the object Python steps.
class PySimulation {
 public:
  // sample_rate < 0: the scene's output.sample_rate.
  PySimulation(const Scene& scene, double sample_rate)
      : sim_(scene),
        sample_rate_(sample_rate < 0.0 ? scene.output.sample_rate : sample_rate),
        recorder_(sim_.model(), sample_rate_),
        lateral_(sim_.model(), sample_rate_) {
    recorder_.record(sim_.model(), sim_.state());
    lateral_.record(sim_.model(), sim_.state());
  }

  // A new pass from the start, recorded at the same sample rate as the first.
  void reset() {
    sim_.reset(true);
    recorder_ = PassRecorder(sim_.model(), sample_rate_);
    recorder_.record(sim_.model(), sim_.state());
    lateral_ = LateralRecorder(sim_.model(), sample_rate_);
    lateral_.record(sim_.model(), sim_.state());
  }

  // Steps up to n times; stops at the end of the pass or a divergence. Returns the steps taken.
  // Called without the GIL: takes the object's lock itself.
  long long step(long long n) {
    std::lock_guard<std::mutex> lock(mutex_);
    return step_locked(n);
  }

  long long step_locked(long long n) {
    if (n < 0) throw py::value_error("step(n): n = " + std::to_string(n) + " rejected: allowed n >= 0");
    long long done = 0;
    for (; done < n && !sim_.finished(); ++done) {
      if (sim_.step() != StepStatus::kOk) break;
      recorder_.record(sim_.model(), sim_.state());
      lateral_.record(sim_.model(), sim_.state());
    }
    if (sim_.state().status == StepStatus::kDiverged) throw std::runtime_error(sim_.status_message());
    return done;
  }

  // To the end of the pass, refused when it would not end within max_steps (speed 0, a crawl).
  // Called without the GIL.
  long long run(double max_steps) {
    std::lock_guard<std::mutex> lock(mutex_);
    // An infinite bound would let a pass at speed 0 run for ever.
    if (!std::isfinite(max_steps))
      throw py::value_error("run(): max_steps = " + fmt_given(max_steps) + " rejected: allowed a finite number");
    const State& st = sim_.state();
    const double left = st.speed > 0.0 ? (sim_.model().train_end - st.front - st.line_offset) / st.speed / sim_.model().dt
                                       : std::numeric_limits<double>::infinity();
    if (!(left <= max_steps)) {
      const std::string note = short_element_note(sim_.model());
      throw py::value_error("run(): max_steps = " + fmt_given(max_steps) + " rejected: the rest of the pass would take " +
                            fmt(std::ceil(left)) + " steps at " + fmt(st.speed) +
                            " m/s; allowed max_steps at least that (set a speed, or step(n) yourself)" +
                            (note.empty() ? "" : "; " + note));
    }
    return step_locked(std::numeric_limits<long long>::max());
  }

  // simulate_pass's stats.json: the pantographs', the line's (steady arms, droppers, limits) and
  // on a 3-D line the lateral plane's.
  std::string statistics_json(double wall_s) const {
    return pass_statistics_json(sim_.model(), sim_.state(), recorder_, RunInfo{wall_s, -1.0, -1}, &lateral_,
                                sim_.state().status == StepStatus::kDewired);
  }

  // simulate_pass's files of the pass in `dir` (core/pass_files: each whole or not at all).
  void write_pass_files(const std::string& dir, double wall_s) const {
    try {
      make_directories(dir);
      catenary_sim::write_pass_files(dir, sim_.model(), sim_.state(), recorder_, RunInfo{wall_s, -1.0, -1}, &lateral_,
                                     sim_.state().status == StepStatus::kDewired);
    } catch (const OutputError& e) {
      throw py::value_error(e.what());
    }
  }

  py::dict series() const {
    py::dict out;
    const auto& rows = recorder_.rows();
    const std::vector<std::string> cols = recorder_.columns();
    py::array_t<double> t(rows.size());
    auto tm = t.mutable_unchecked<1>();
    for (std::size_t i = 0; i < rows.size(); ++i) tm(i) = rows[i].time;
    out["time_s"] = t;
    for (std::size_t c = 0; c < cols.size(); ++c) {
      py::array_t<double> a(rows.size());
      auto am = a.mutable_unchecked<1>();
      for (std::size_t i = 0; i < rows.size(); ++i) am(i) = rows[i].values[c];
      out[py::str(cols[c])] = a;
    }
    return out;
  }

  void command(bool ok, const std::string& err) {
    if (!ok) throw py::value_error(err);  // the state is as it was (Simulation's guarantee)
  }

  Simulation sim_;
  double sample_rate_;  // Hz of the recorded series (0: every step)
  PassRecorder recorder_;
  LateralRecorder lateral_;  // records nothing on a 2-D line
  // step() and run() release the GIL, so other Python threads may call into the same object
  // meanwhile: every call holds this lock while it touches the pass.
  mutable std::mutex mutex_;
};

// Takes a simulation's lock for a call that holds the GIL. Waits for it without the GIL: the
// holder may be a call like this one, which took the lock and now waits for the GIL (a deadlock if
// the GIL were kept while waiting), or a step() that runs for long (other threads run meanwhile).
class Locked {
 public:
  explicit Locked(const PySimulation& s) : lock_(s.mutex_, std::defer_lock) {
    if (!lock_.try_lock()) {
      py::gil_scoped_release nogil;
      lock_.lock();
    }
  }

 private:
  std::unique_lock<std::mutex> lock_;
};

void check_sample_rate(double sample_rate) {
  if (!std::isfinite(sample_rate) || (sample_rate < 0.0 && sample_rate != -1.0))
    throw py::value_error("sample_rate = " + fmt_given(sample_rate) + " rejected: allowed >= 0 Hz (0: every step)");
}

using PyClass = py::class_<PySimulation>;

// The module's own names: the scene exception, the commands' ranges, the scene checks.
void bind_scene_checks(py::module& m) {
  py::register_exception<SceneError>(m, "_SceneError", PyExc_ValueError);
  // The commands' ranges (the core's), for the Python side's messages about arguments of a wrong type.
  m.attr("_MAX_SPEED") = Simulation::kMaxSpeed;
  m.attr("_MAX_UPLIFT") = Simulation::kMaxUplift;
  m.attr("_MIN_EXTERNAL_FORCE") = Simulation::kMinExternalForce;
  m.attr("_MAX_EXTERNAL_FORCE") = Simulation::kMaxExternalForce;

  m.def(
      "_check_scene_string",
      [](const std::string& yaml, const std::vector<std::string>& overrides, const std::string& base_dir) {
        load_scene_string(yaml, overrides, base_dir);
      },
      py::arg("yaml"), py::arg("overrides"), py::arg("base_dir") = "");
  // The statistics' filter, so that a measured record and a simulated pass go through the same one.
  m.def(
      "_lowpass_zero_phase",
      [](const std::vector<double>& x, double fs, double fc) {
        if (!(std::isfinite(fs) && fs > 0.0))
          throw py::value_error("sample rate fs = " + fmt_given(fs) + " Hz rejected: allowed a finite rate > 0 Hz");
        if (!(std::isfinite(fc) && fc >= kLeastFilterCutoff))
          throw py::value_error("cutoff fc = " + fmt_given(fc) + " Hz rejected: allowed a finite frequency of at least " +
                                fmt(kLeastFilterCutoff) + " Hz (below it the filter does not settle within a record)");
        for (std::size_t i = 0; i < x.size(); ++i)
          if (!std::isfinite(x[i]))
            throw py::value_error("sample " + std::to_string(i) + " = " + fmt_given(x[i]) + " rejected: allowed finite values");
        return lowpass_zero_phase(x, fs, fc);
      },
      py::arg("x"), py::arg("fs"), py::arg("fc"));
  m.def(
      "_check_scene_file",
      [](const std::string& path, const std::vector<std::string>& overrides) { load_scene_file(path, overrides); },
      py::arg("path"), py::arg("overrides"));
}

// A pass: made from a scene, stepped, run to the end, its statistics, files and series, reset.
void bind_pass(PyClass& c) {
  c.def(py::init([](const std::string& yaml, const std::vector<std::string>& overrides, double sample_rate) {
             check_sample_rate(sample_rate);
             return std::make_unique<PySimulation>(load_scene_string(yaml, overrides), sample_rate);
           }),
           py::arg("yaml"), py::arg("overrides"), py::arg("sample_rate"))
      .def_static("from_file", [](const std::string& path, const std::vector<std::string>& overrides, double sample_rate) {
             check_sample_rate(sample_rate);
             return std::make_unique<PySimulation>(load_scene_file(path, overrides), sample_rate);
           },
           py::arg("path"), py::arg("overrides"), py::arg("sample_rate"))
      .def("step", &PySimulation::step, py::arg("n") = 1, py::call_guard<py::gil_scoped_release>())
      // The whole pass without the GIL: other Python threads (a Dask worker's heartbeats) run meanwhile.
      .def("run", &PySimulation::run, py::arg("max_steps") = 2e7, py::call_guard<py::gil_scoped_release>())
      .def("statistics_json", [](const PySimulation& s, double wall_s) { Locked l(s); return s.statistics_json(wall_s); },
           py::arg("wall_s") = 0.0)
      .def("write_pass_files", [](const PySimulation& s, const std::string& dir, double wall_s) {
             Locked l(s);
             s.write_pass_files(dir, wall_s);
           }, py::arg("dir"), py::arg("wall_s") = 0.0)
      .def("series", [](const PySimulation& s) { Locked l(s); return s.series(); })
      .def("finished", [](const PySimulation& s) { Locked l(s); return s.sim_.finished(); })
      .def("reset", [](PySimulation& s) { Locked l(s); s.reset(); });
}

// What the pass is and where it stands: its clock, train, status, pantographs, steady arms and wires.
void bind_pass_description(PyClass& c) {
  c.def_property_readonly("time", [](const PySimulation& s) { Locked l(s); return s.sim_.state().time; })
      .def_property_readonly("steps", [](const PySimulation& s) { Locked l(s); return static_cast<long long>(s.sim_.state().steps); })
      .def_property_readonly("dt", [](const PySimulation& s) { Locked l(s); return s.sim_.model().dt; })
      .def_property_readonly("dofs", [](const PySimulation& s) { Locked l(s); return s.sim_.model().n_dof; })
      .def_property_readonly("speed", [](const PySimulation& s) { Locked l(s); return s.sim_.state().speed; })
      .def_property_readonly("front", [](const PySimulation& s) { Locked l(s); return s.sim_.state().front + s.sim_.state().line_offset; })
      .def_property_readonly("status", [](const PySimulation& s) { Locked l(s); return s.sim_.status_message(); })
      .def_property_readonly("pantograph_names", [](const PySimulation& s) {
        Locked l(s);
        std::vector<std::string> n;
        for (const Pantograph& p : s.sim_.model().pantographs) n.push_back(p.name);
        return n;
      })
      // Steady arms (constant geometry, for plots of their uplift from a recorded wire_shape): the
      // contact wire, the station in the model's stations (on an endless line add the line offset:
      // a wire_shape's stations[0] minus wire_start_m), the design height and the wire's first station.
      .def_property_readonly("steady_arms", [](const PySimulation& s) {
        Locked l(s);
        const Model& m = s.sim_.model();
        py::list out;
        for (const SupportSpring& sp : m.springs) {
          if (!sp.steady_arm) continue;
          const Wire& w = m.wires[wire_holding(m, sp.dof)];
          py::dict d;
          d["wire"] = w.name;
          d["station_m"] = sp.x;
          d["design_height_m"] = w.height[sp.dof - w.w_dof];
          d["wire_start_m"] = w.x.front();
          out.append(d);
        }
        return out;
      })
      .def_property_readonly("external_pantographs", [](const PySimulation& s) {
        Locked l(s);
        std::vector<int> n;
        for (std::size_t i = 0; i < s.sim_.model().pantographs.size(); ++i)
          if (s.sim_.model().pantographs[i].external) n.push_back(static_cast<int>(i));
        return n;
      })
      .def_property_readonly("contact_wire_names", [](const PySimulation& s) {
        Locked l(s);
        std::vector<std::string> n;
        for (int w : s.sim_.model().contact_wires) n.push_back(s.sim_.model().wires[w].name);
        return n;
      });
}

// What the state is now: displacements, velocities, contact forces, and one pantograph's state.
// The first three are views (read-only, no copy) of the state: they change as the simulation steps.
void bind_state_views(PyClass& c) {
  c.def_property_readonly("displacements", [](py::object self) {
        const PySimulation& s = self.cast<const PySimulation&>();
        Locked l(s);
        return view(s.sim_.state().u.data(), static_cast<std::size_t>(s.sim_.state().u.size()), self);
      })
      .def_property_readonly("velocities", [](py::object self) {
        const PySimulation& s = self.cast<const PySimulation&>();
        Locked l(s);
        return view(s.sim_.state().v.data(), static_cast<std::size_t>(s.sim_.state().v.size()), self);
      })
      .def_property_readonly("contact_forces", [](py::object self) {
        const PySimulation& s = self.cast<const PySimulation&>();
        Locked l(s);
        const auto& f = s.sim_.state().contact_force;
        py::array_t<double> a = view(f.data(), f.size(), self);
        const std::size_t nw = s.sim_.model().contact_wires.size();
        return a.reshape({static_cast<py::ssize_t>(f.size() / nw), static_cast<py::ssize_t>(nw)});
      })
      .def("pantograph_state", [](const PySimulation& s, int i) {
        Locked l(s);
        const Model& m = s.sim_.model();
        if (i < 0 || i >= static_cast<int>(m.pantographs.size()))
          throw py::index_error("pantograph index " + std::to_string(i) + " rejected: allowed 0 to " +
                                std::to_string(m.pantographs.size() - 1));
        const State& st = s.sim_.state();
        py::dict d;
        d["name"] = m.pantographs[i].name;
        d["position_m"] = pantograph_position(m, st, i);
        d["contact_force_N"] = total_contact_force(m, st, i);
        d["head_height_m"] = head_height(m, st, i);
        d["uplift_N"] = st.uplift[i];
        d["aero_uplift_N"] = frame_aero_uplift(m, st, i);  // on the frame, at the speed through the air
        d["head_wind_m_s"] = st.head_wind[i];               // the wind against the direction of travel
        // Every head (several on their own suspensions; a chain's first mass; none for a moving
        // force): its height, the force on its strips and its own aero uplift.
        py::list heights, forces, aero;
        for (int h = 0; h < head_count(m, i); ++h) {
          heights.append(head_height(m, st, i, h));
          forces.append(st.head_contact_force(m, i, h));
          aero.append(head_aero_uplift(m, st, i, h));
        }
        d["head_heights_m"] = heights;
        d["head_contact_forces_N"] = forces;
        d["head_aero_uplift_N"] = aero;
        d["knee"] = m.scene.pantographs[i].knee_trailing ? "trailing" : "leading";
        return d;
      }, py::arg("index") = 0);
}

// The commands, refused as the core refuses them (the state is then as it was).
void bind_commands(PyClass& c) {
  c.def("set_speed", [](PySimulation& s, double v) {
        Locked l(s);
        std::string e;
        s.command(s.sim_.set_target_speed(v, &e), e);
      }, py::arg("speed_mps"))
      .def("set_max_acceleration", [](PySimulation& s, double a) {
        Locked l(s);
        std::string e;
        s.command(s.sim_.set_max_acceleration(a, &e), e);
      }, py::arg("accel_mps2"))
      // pantograph -1: every pantograph. Other negative indexes are refused: the core would take any
      // of them as every pantograph, and -2 is no such wish.
      .def("set_uplift", [](PySimulation& s, double f, int i) {
        Locked l(s);
        const int np = static_cast<int>(s.sim_.model().pantographs.size());
        if (i < -1 || i >= np)
          throw py::value_error("pantograph index " + std::to_string(i) + " rejected: allowed 0 to " +
                                std::to_string(np - 1) + ", or -1 for every pantograph");
        std::string e;
        s.command(s.sim_.set_uplift(i, f, &e), e);
      }, py::arg("force_n"), py::arg("pantograph") = -1)
      .def("set_external_force", [](PySimulation& s, double f, int i) {
        Locked l(s);
        std::string e;
        s.command(s.sim_.set_external_force(i, f, &e), e);
      }, py::arg("force_n"), py::arg("pantograph") = 0);
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "catenary_sim core (pybind11): scenes, passes, stepping; see catenary_sim.__doc__";
  bind_scene_checks(m);
  PyClass sim(m, "_Simulation");
  bind_pass(sim);
  bind_pass_description(sim);
  bind_state_views(sim);
  bind_commands(sim);
}
