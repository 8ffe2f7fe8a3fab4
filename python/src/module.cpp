// qs._qs: the extension behind the Python package qs, over the library facade (qs::pipeline)
// and the library's measures. numpy arrays in (checked: shape, dtype, contiguity, finiteness,
// index ranges) and out (read-only views of the results where they hold the data already).
// Long calls run on a worker thread with the GIL released; the calling thread polls for signals
// (Ctrl-C) and raises the library's cancel flag. The user-facing docs are in python/qs/__init__.py.

#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <fstream>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include "json_reports.h"
#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/correspondence/dissection_measure.h"
#include "qs/dissect/chart_io.h"
#include "qs/bake/bake.h"
#include "qs/bake/bake_folder.h"
#include "qs/core/output_folder.h"
#include "qs/merge/merge.h"
#include "qs/metro/metro.h"
#include "qs/morph/blend.h"
#include "qs/morph/morph_glb.h"
#include "qs/remesh/chart_sampler.h"
#include "qs/remesh/quality.h"
#include "qs/pipeline/pipeline.h"

namespace py = pybind11;
namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------------------------------------
// Exceptions: qs.Error and its subclasses, one per exit code.

PyObject* g_error = nullptr;
PyObject* g_usage = nullptr;
PyObject* g_invalid = nullptr;
PyObject* g_io = nullptr;
PyObject* g_solver = nullptr;
PyObject* g_internal = nullptr;

PyObject* make_exception(py::module_& m, const char* name, PyObject* bases, const char* doc) {
  const std::string full = std::string("qs.") + name;
  PyObject* e = PyErr_NewExceptionWithDoc(full.c_str(), doc, bases, nullptr);
  if (!e) throw py::error_already_set();
  m.add_object(name, py::handle(e));
  return e;
}

PyObject* exception_for(qs::ErrorCode code) {
  switch (code) {
    case qs::ErrorCode::Usage: return g_usage;
    case qs::ErrorCode::InvalidInput: return g_invalid;
    case qs::ErrorCode::Io: return g_io;
    case qs::ErrorCode::Solver: return g_solver;
    case qs::ErrorCode::Internal: return g_internal;
  }
  return g_error;
}

[[noreturn]] void invalid(const std::string& m) { throw qs::InvalidInput(m); }

// ---------------------------------------------------------------------------------------------
// Long calls: a worker thread does the work; this thread, without the GIL, waits for it and
// every 50 ms runs Python's signal handlers (PyErr_CheckSignals). A KeyboardInterrupt (or any
// exception from a handler or from the progress callback) raises the cancel flag; the library
// stops at its next check and the Python exception is raised here.

struct LongCall {
  std::atomic<bool> cancel{false};
  std::mutex mutex;
  std::exception_ptr python_error;  // from a signal handler or the progress callback

  void fail_with_python_error() {
    std::lock_guard<std::mutex> lock(mutex);
    if (!python_error) python_error = std::current_exception();
    cancel = true;
  }
};

template <class F>
auto run_long(const py::object& progress, int threads, F&& work) -> decltype(work(std::declval<const qs::Context&>())) {
  using R = decltype(work(std::declval<const qs::Context&>()));
  if (threads < 0) throw qs::UsageError("threads must be at least 0 (0: all hardware threads)");
  auto call = std::make_shared<LongCall>();
  qs::Context ctx;
  ctx.threads = threads;
  ctx.cancel = &call->cancel;
  if (!progress.is_none()) {
    if (!PyCallable_Check(progress.ptr())) throw qs::UsageError("progress must be callable as progress(stage, fraction)");
    // Shared, so that the library's copies of the context never touch the callable's reference
    // count without the GIL; the last reference goes in this thread, with the GIL.
    auto cb = std::make_shared<py::object>(progress);
    ctx.progress = [call, cb](const std::string& stage, double fraction) {
      if (call->cancel) return;
      py::gil_scoped_acquire gil;
      try {
        (*cb)(stage, fraction);
      } catch (py::error_already_set&) {
        call->fail_with_python_error();
      }
    };
  }
  std::optional<R> result;
  std::exception_ptr library_error;
  bool done = false;
  std::mutex m;
  std::condition_variable cv;
  {
    py::gil_scoped_release release;
    std::thread worker([&] {
      try {
        result.emplace(work(ctx));
      } catch (...) {
        library_error = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(m);
      done = true;
      cv.notify_all();
    });
    std::unique_lock<std::mutex> lock(m);
    while (!cv.wait_for(lock, std::chrono::milliseconds(50), [&] { return done; })) {
      lock.unlock();
      {
        py::gil_scoped_acquire gil;
        if (!call->cancel && PyErr_CheckSignals() != 0) {
          try {
            throw py::error_already_set();
          } catch (py::error_already_set&) {
            call->fail_with_python_error();
          }
        }
      }
      lock.lock();
    }
    lock.unlock();
    worker.join();
  }
  ctx.progress = nullptr;
  if (call->python_error) std::rethrow_exception(call->python_error);
  if (library_error) std::rethrow_exception(library_error);
  return std::move(*result);
}

// ---------------------------------------------------------------------------------------------
// Arrays

// A read-only numpy view of `n` rows of `cols` values of T at `data`, kept alive by `owner`.
template <class T>
py::array_t<T> view(const T* data, size_t n, size_t cols, py::handle owner) {
  py::array_t<T> a({n, cols}, {cols * sizeof(T), sizeof(T)}, data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

std::string shape_of(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

py::array as_array(const py::handle& h, const char* what) {
  if (!py::isinstance<py::array>(h))
    throw qs::InvalidInput(std::string(what) + ": expected a numpy array, got " +
                           std::string(py::str(py::type::handle_of(h).attr("__name__"))));
  return py::reinterpret_borrow<py::array>(h);
}

void check_rows(const py::array& a, const char* what, const char* expected) {
  if (a.ndim() != 2 || a.shape(1) != 3)
    throw qs::InvalidInput(std::string(what) + ": expected shape " + expected + ", got " + shape_of(a));
  if (!(a.flags() & py::array::c_style))
    throw qs::InvalidInput(std::string(what) + ": the array is not C-contiguous (pass np.ascontiguousarray(...))");
}

std::vector<qs::Vec3> vertices_from(const py::handle& h, const char* what) {
  const py::array a = as_array(h, what);
  check_rows(a, what, "(n, 3)");
  const py::dtype dt = a.dtype();
  if (dt.kind() != 'f' || (dt.itemsize() != 8 && dt.itemsize() != 4))
    throw qs::InvalidInput(std::string(what) + ": expected float64 (or float32) values, got dtype " +
                           std::string(py::str(py::handle(dt))));
  const auto n = static_cast<size_t>(a.shape(0));
  std::vector<qs::Vec3> out(n);
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      const double x = dt.itemsize() == 8 ? static_cast<const double*>(a.data())[3 * i + k]
                                          : static_cast<const float*>(a.data())[3 * i + k];
      if (!std::isfinite(x))
        invalid(std::string(what) + "[" + std::to_string(i) + ", " + std::to_string(k) + "] is " +
                (std::isnan(x) ? "nan" : "infinite") + ": coordinates must be finite");
      out[i][k] = x;
    }
  return out;
}

std::vector<qs::Tri> faces_from(const py::handle& h, size_t num_vertices, const char* what) {
  const py::array a = as_array(h, what);
  check_rows(a, what, "(m, 3)");
  const py::dtype dt = a.dtype();
  if ((dt.kind() != 'i' && dt.kind() != 'u') || (dt.itemsize() != 4 && dt.itemsize() != 8))
    throw qs::InvalidInput(std::string(what) + ": expected int32 (or int64) vertex indices, got dtype " +
                           std::string(py::str(py::handle(dt))));
  const auto m = static_cast<size_t>(a.shape(0));
  std::vector<qs::Tri> out(m);
  for (size_t f = 0; f < m; ++f)
    for (int k = 0; k < 3; ++k) {
      long long v;
      if (dt.itemsize() == 4)
        v = dt.kind() == 'i' ? static_cast<const int32_t*>(a.data())[3 * f + k]
                             : static_cast<long long>(static_cast<const uint32_t*>(a.data())[3 * f + k]);
      else if (dt.kind() == 'i') v = static_cast<const int64_t*>(a.data())[3 * f + k];
      else {
        const uint64_t u = static_cast<const uint64_t*>(a.data())[3 * f + k];
        if (u >= static_cast<uint64_t>(num_vertices))
          invalid(std::string(what) + "[" + std::to_string(f) + ", " + std::to_string(k) + "] = " + std::to_string(u) +
                  " is not a vertex index: expected 0 to " + std::to_string(static_cast<long long>(num_vertices) - 1));
        v = static_cast<long long>(u);
      }
      if (v < 0 || v >= static_cast<long long>(num_vertices))
        invalid(std::string(what) + "[" + std::to_string(f) + ", " + std::to_string(k) + "] = " + std::to_string(v) +
                " is not a vertex index: expected 0 to " + std::to_string(static_cast<long long>(num_vertices) - 1));
      out[f][k] = static_cast<int>(v);
    }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Objects

/// A mesh as read or given, with its validation (the mesh dissect uses is valid.mesh).
struct Mesh {
  std::string name;
  qs::io::ReadResult read;
  qs::mesh::ValidationResult valid;
};

std::shared_ptr<Mesh> make_mesh(qs::TriMesh mesh, const std::string& name) {
  auto m = std::make_shared<Mesh>();
  m->name = name;
  m->read.mesh = std::move(mesh);
  m->valid = qs::mesh::validate(m->read.mesh);
  return m;
}

/// Landmarks as text (the landmark JSON or a MeshLab .pp), resolved on each mesh they are used with.
struct Landmarks {
  std::string text;
  qs::landmarks::LandmarkFormat format = qs::landmarks::LandmarkFormat::Json;
  std::string source;  ///< the file, or the name given
};

qs::landmarks::Landmarks resolve(const Landmarks& l, const Mesh& m) {
  if (!m.valid.report.accepted)
    throw qs::InvalidInput("mesh rejected:\n" + qs::mesh::format_report(m.name, m.valid.report));
  return qs::landmarks::parse_landmarks(l.text, l.format, l.source, m.valid);
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw qs::IoError(p.string() + ": cannot open");
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw qs::IoError(p.string() + ": cannot read");
  return s.str();
}

/// A dissected set: computed (result) or loaded from a folder (loaded, with its files' bytes).
struct Dissection {
  std::optional<qs::pipeline::DissectResult> result;
  qs::dissect::LoadedDissection loaded;  // the charts remesh uses (from result, or read)
  std::optional<fs::path> folder;        // where it was saved or loaded from
  std::vector<std::pair<std::string, std::string>> files;  // loaded: name -> bytes
};

struct Remesh {
  qs::pipeline::RemeshResult result;
  std::optional<fs::path> dissection_folder;
  std::optional<fs::path> folder;  // where it was saved
};

}  // namespace

PYBIND11_MODULE(_qs, m) {
  m.doc() = "qs: consistent quad dissections of genus-0 meshes (the extension; see the package qs)";

  // Exceptions ------------------------------------------------------------------------------
  g_error = make_exception(m, "Error", PyExc_Exception, "Base of every error qs raises on purpose.");
  g_usage = make_exception(m, "UsageError", g_error, "A bad option or call (the tools' exit code 1).");
  g_invalid = make_exception(m, "InvalidInput", py::make_tuple(py::handle(g_error), py::handle(PyExc_ValueError)).release().ptr(),
                             "A mesh, landmarks, array or folder qs cannot use (exit code 2).");
  g_io = make_exception(m, "IoError", py::make_tuple(py::handle(g_error), py::handle(PyExc_OSError)).release().ptr(),
                        "A file that cannot be opened, read or written (exit code 3).");
  g_solver = make_exception(m, "SolverError", py::make_tuple(py::handle(g_error), py::handle(PyExc_RuntimeError)).release().ptr(),
                            "A numerical step that failed, e.g. folded maps (exit code 4).");
  g_internal = make_exception(m, "InternalError", py::make_tuple(py::handle(g_error), py::handle(PyExc_RuntimeError)).release().ptr(),
                              "A bug in qs (exit code 70): please report it.");
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const qs::Error& e) {
      PyErr_SetString(exception_for(e.code()), e.what());
    } catch (const std::filesystem::filesystem_error& e) {
      PyErr_SetString(g_io, e.what());
    }
  });

  // Meshes ----------------------------------------------------------------------------------
  py::class_<Mesh, std::shared_ptr<Mesh>>(m, "Mesh")
      .def(py::init([](const py::object& vertices, const py::object& faces, const std::string& name) {
             std::vector<qs::Vec3> v = vertices_from(vertices, "vertices");
             std::vector<qs::Tri> f = faces_from(faces, v.size(), "faces");
             return make_mesh(qs::TriMesh{std::move(v), std::move(f)}, name);
           }),
           py::arg("vertices"), py::arg("faces"), py::arg("name") = "mesh")
      .def_readonly("name", &Mesh::name)
      .def_property_readonly("vertices", [](py::object self) {
        const auto& m = self.cast<const Mesh&>();
        return view<double>(m.read.mesh.positions.empty() ? nullptr : m.read.mesh.positions[0].data(),
                            m.read.mesh.positions.size(), 3, self);
      })
      .def_property_readonly("faces", [](py::object self) {
        const auto& m = self.cast<const Mesh&>();
        return view<int>(m.read.mesh.faces.empty() ? nullptr : m.read.mesh.faces[0].data(), m.read.mesh.faces.size(), 3,
                         self);
      })
      .def_property_readonly("accepted", [](const Mesh& m) { return m.valid.report.accepted; })
      .def_property_readonly("report", [](const Mesh& m) { return qs::mesh::format_report(m.name, m.valid.report); })
      .def("_inspect_json", [](const Mesh& m) {
        nlohmann::json j;
        j["file"] = m.name;
        j["read"] = qs::tools::to_json(m.read.report);
        j["validation"] = qs::tools::to_json(m.valid.report);
        j["accepted"] = m.valid.report.accepted;
        return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
      })
      .def("__repr__", [](const Mesh& m) {
        return "<qs.Mesh '" + m.name + "': " + std::to_string(m.read.mesh.num_vertices()) + " vertices, " +
               std::to_string(m.read.mesh.num_faces()) + " faces, " + (m.valid.report.accepted ? "accepted" : "rejected") +
               ">";
      });

  m.def("read_mesh", [](const std::string& path) {
    auto m = std::make_shared<Mesh>();
    m->name = path;
    m->read = qs::io::read_mesh(path);
    m->valid = qs::mesh::validate(m->read.mesh);
    return m;
  }, py::arg("path"));

  // Landmarks -------------------------------------------------------------------------------
  py::class_<Landmarks, std::shared_ptr<Landmarks>>(m, "_Landmarks")
      .def_readonly("source", &Landmarks::source)
      .def_readonly("text", &Landmarks::text)
      .def("_resolve_json", [](const Landmarks& l, const Mesh& mesh) {
        const auto r = resolve(l, mesh);
        nlohmann::json j;
        j["seeds"] = nlohmann::json::array();
        for (const auto& s : r.seeds) j["seeds"].push_back(qs::tools::to_json(s));
        j["features"] = nlohmann::json::array();
        for (const auto& f : r.features) j["features"].push_back(qs::tools::to_json(f));
        return j.dump();
      });
  m.def("_landmarks_from_text", [](const std::string& text, const std::string& name) {
    auto l = std::make_shared<Landmarks>();
    l->text = text;
    l->source = name;
    return l;
  });
  m.def("_read_landmarks", [](const std::string& path, const Mesh& mesh) {
    if (!mesh.valid.report.accepted)
      throw qs::InvalidInput("mesh rejected:\n" + qs::mesh::format_report(mesh.name, mesh.valid.report));
    qs::landmarks::read_landmarks(path, mesh.valid);  // its errors, as the tools give them
    auto l = std::make_shared<Landmarks>();
    l->text = slurp(path);
    std::string ext = fs::path(path).extension().string();
    for (auto& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    l->format = ext == ".pp" ? qs::landmarks::LandmarkFormat::PickedPoints : qs::landmarks::LandmarkFormat::Json;
    l->source = path;
    return l;
  });

  // Dissection ------------------------------------------------------------------------------
  py::class_<Dissection, std::shared_ptr<Dissection>>(m, "_Dissection")
      .def_property_readonly("folder", [](const Dissection& d) -> py::object {
        if (!d.folder) return py::none();
        return py::str(d.folder->string());
      })
      .def_property_readonly("files", [](const Dissection& d) {
        std::vector<std::string> out;
        for (const auto& dm : d.loaded.meshes) out.push_back(dm.file);
        return out;
      })
      .def_property_readonly("chart_files", [](const Dissection& d) {
        std::vector<std::string> out;
        for (const auto& dm : d.loaded.meshes) out.push_back(dm.chart_file);
        return out;
      })
      .def_property_readonly("num_patches", [](const Dissection& d) {
        return d.loaded.meshes.empty() ? 0 : static_cast<int>(d.loaded.meshes[0].dissection.chart.patches.size());
      })
      .def_property_readonly("patch_names", [](const Dissection& d) {
        std::vector<std::string> out;
        if (!d.loaded.meshes.empty())
          for (const auto& p : d.loaded.meshes[0].dissection.chart.patches) out.push_back(p.name);
        return out;
      })
      .def_property_readonly("report", [](const Dissection& d) { return d.result ? d.result->report : std::string(); })
      .def_property_readonly("maps", [](const Dissection& d) { return d.result ? d.result->maps : std::string(); })
      .def_property_readonly("folded_faces", [](const Dissection& d) { return d.result ? d.result->folded_faces : 0; })
      .def("check_bijective", [](const Dissection& d) {
        if (d.result) qs::pipeline::check_bijective(*d.result);
      })
      .def("_chart", [](py::object self, int i) {
        const auto& d = self.cast<const Dissection&>();
        if (i < 0 || i >= static_cast<int>(d.loaded.meshes.size()))
          throw qs::UsageError("chart " + std::to_string(i) + ": the dissection has " +
                               std::to_string(d.loaded.meshes.size()) + " meshes");
        const qs::dissect::Chart& c = d.loaded.meshes[static_cast<size_t>(i)].dissection.chart;
        py::dict out;
        out["vertices"] = view<double>(c.mesh.positions.empty() ? nullptr : c.mesh.positions[0].data(),
                                       c.mesh.positions.size(), 3, self);
        out["faces"] = view<int>(c.mesh.faces.empty() ? nullptr : c.mesh.faces[0].data(), c.mesh.faces.size(), 3, self);
        py::array_t<double> uv({c.face_uv.size(), size_t{3}, size_t{2}});
        auto u = uv.mutable_unchecked<3>();
        for (size_t f = 0; f < c.face_uv.size(); ++f)
          for (int k = 0; k < 3; ++k) u(f, k, 0) = c.face_uv[f][k].x(), u(f, k, 1) = c.face_uv[f][k].y();
        out["face_uv"] = uv;
        py::array_t<int> fp(c.face_patch.size());
        std::copy(c.face_patch.begin(), c.face_patch.end(), fp.mutable_data());
        out["face_patch"] = fp;
        return out;
      }, py::arg("i"))
      .def("save", [](Dissection& d, const std::string& folder) {
        if (d.result) {
          qs::pipeline::write_dissection(*d.result, fs::path(folder));
        } else {
          qs::OutputFolder out(folder);
          for (const auto& [name, bytes] : d.files) {
            qs::check_not_an_input(out.target() / name, {*d.folder / name}, "output");
            std::ofstream f(out.staging() / name, std::ios::binary);
            f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
            f.close();
            if (!f) throw qs::IoError((out.staging() / name).string() + ": cannot write");
          }
          out.commit();
        }
        d.folder = fs::path(folder);
      }, py::arg("folder"));

  m.def("_load_dissection", [](const std::string& folder) {
    auto d = std::make_shared<Dissection>();
    d->loaded = qs::pipeline::read_dissection(folder);
    d->folder = fs::path(folder);
    d->files.emplace_back("dissection.json", slurp(fs::path(folder) / "dissection.json"));
    for (const auto& dm : d->loaded.meshes) d->files.emplace_back(dm.chart_file, slurp(fs::path(folder) / dm.chart_file));
    return d;
  }, py::arg("folder"));

  m.def("_dissect", [](const std::vector<std::shared_ptr<Mesh>>& meshes, const std::vector<py::object>& landmarks,
                       const std::string& options_json, int threads, const py::object& progress) {
    if (meshes.empty()) throw qs::InvalidInput("no mesh to dissect");
    if (!landmarks.empty() && landmarks.size() != meshes.size())
      throw qs::UsageError("landmarks: got " + std::to_string(landmarks.size()) + " for " +
                           std::to_string(meshes.size()) + " meshes; give one per mesh (None for none), in the same order");
    const qs::pipeline::DissectConfig config = qs::pipeline::config_from_json(options_json, "the options");
    qs::pipeline::validate_config(config);
    std::vector<qs::pipeline::Input> inputs(meshes.size());
    for (size_t i = 0; i < meshes.size(); ++i) {
      if (!meshes[i]) throw qs::UsageError("meshes[" + std::to_string(i) + "] is None");
      const Mesh& mesh = *meshes[i];
      if (!mesh.valid.report.accepted)
        throw qs::InvalidInput("mesh rejected:\n" + qs::mesh::format_report(mesh.name, mesh.valid.report));
      auto& in = inputs[i];
      in.file = mesh.name;
      in.read = mesh.read;
      in.valid = mesh.valid;
      if (!landmarks.empty() && !landmarks[i].is_none()) {
        const auto& l = landmarks[i].cast<const Landmarks&>();
        in.landmarks = resolve(l, mesh);
        in.landmark_file = l.source;
      }
    }
    auto d = std::make_shared<Dissection>();
    d->result = run_long(progress, threads,
                         [&](const qs::Context& ctx) { return qs::pipeline::dissect(inputs, config, ctx); });
    d->loaded.options = config.dissect;
    d->loaded.meshes = d->result->meshes;
    return d;
  });

  m.def("_config_json", [](const std::string& options_json) {
    return qs::pipeline::config_to_json(qs::pipeline::config_from_json(options_json, "the options"));
  });
  m.def("_describe_config", &qs::pipeline::describe_config);

  // Remesh ----------------------------------------------------------------------------------
  py::class_<Remesh, std::shared_ptr<Remesh>>(m, "_Remesh")
      .def_property_readonly("faces", [](py::object self) {
        const auto& f = self.cast<const Remesh&>().result.set.connectivity.faces;
        return view<int>(f.empty() ? nullptr : f[0].data(), f.size(), 3, self);
      })
      .def_property_readonly("positions", [](py::object self) {
        const auto& r = self.cast<const Remesh&>();
        py::list out;
        for (const auto& p : r.result.set.positions) out.append(view<double>(p.empty() ? nullptr : p[0].data(), p.size(), 3, self));
        return out;
      })
      .def_property_readonly("vertex_patch", [](const Remesh& r) {
        const auto& c = r.result.set.connectivity;
        py::array_t<int> a(c.vertex_patch.size());
        std::copy(c.vertex_patch.begin(), c.vertex_patch.end(), a.mutable_data());
        return a;
      })
      .def_property_readonly("vertex_uv", [](const Remesh& r) {
        const auto& c = r.result.set.connectivity;
        py::array_t<double> a({c.vertex_uv.size(), size_t{2}});
        auto u = a.mutable_unchecked<2>();
        for (size_t v = 0; v < c.vertex_uv.size(); ++v) u(v, 0) = c.vertex_uv[v].x(), u(v, 1) = c.vertex_uv[v].y();
        return a;
      })
      .def_property_readonly("quads", [](const Remesh& r) -> py::object {
        const auto& q = r.result.set.connectivity.quads;
        if (!r.result.config.quads) return py::none();
        py::array_t<int> a({q.size(), size_t{4}});
        auto u = a.mutable_unchecked<2>();
        for (size_t i = 0; i < q.size(); ++i)
          for (int k = 0; k < 4; ++k) u(i, k) = q[i][k];
        return a;
      })
      .def_property_readonly("outputs", [](const Remesh& r) { return r.result.outputs; })
      .def_property_readonly("report", [](const Remesh& r) { return r.result.report; })
      .def_property_readonly("_meshes_json", [](const Remesh& r) {
        std::string s = "[";
        for (size_t i = 0; i < r.result.mesh_json.size(); ++i) s += (i ? "," : "") + r.result.mesh_json[i];
        return s + "]";
      })
      .def_property_readonly("folder", [](const Remesh& r) -> py::object {
        if (!r.folder) return py::none();
        return py::str(r.folder->string());
      })
      .def("save", [](Remesh& r, const std::string& folder) {
        if (!r.dissection_folder)
          throw qs::UsageError("save the dissection first (Dissection.save(folder)): remesh.json names the dissection "
                               "folder that qs-bake and qs-morph read the charts from");
        qs::pipeline::write_remesh(r.result, fs::path(folder));
        r.folder = fs::path(folder);
      }, py::arg("folder"));

  m.def("_remesh", [](const std::shared_ptr<Dissection>& d, const std::string& mode, int level, const std::string& cells,
                      double adaptive, int max_level, bool quads, const std::string& diagonals, double grid_relax,
                      const std::string& format, bool error, long metro_samples, int threads, const py::object& progress) {
    if (!d) throw qs::UsageError("remesh: the dissection is None");
    using Mode = qs::pipeline::RemeshConfig::Mode;
    qs::pipeline::RemeshConfig config;
    if (mode == "even") config.mode = Mode::Even;
    else if (mode == "uniform") config.mode = Mode::Uniform;
    else if (mode == "adaptive") config.mode = Mode::Adaptive;
    else throw qs::UsageError("mode '" + mode + "': expected even, uniform or adaptive");
    if (cells != "aniso" && cells != "square") throw qs::UsageError("cells '" + cells + "': expected aniso or square");
    if (diagonals != "angle" && diagonals != "pattern")
      throw qs::UsageError("diagonals '" + diagonals + "': expected angle or pattern");
    config.level = level;
    config.square_cells = cells == "square";
    config.adaptive = adaptive;
    config.max_level = max_level;
    config.quads = quads;
    config.pattern_diagonals = diagonals == "pattern";
    config.grid_relax = grid_relax;
    config.format = format;
    config.error = error;
    config.metro_samples = metro_samples;
    qs::pipeline::validate_config(config);
    auto r = std::make_shared<Remesh>();
    r->dissection_folder = d->folder;
    const fs::path folder = d->folder ? *d->folder : fs::path();
    r->result = run_long(progress, threads, [&](const qs::Context& ctx) {
      return qs::pipeline::remesh(d->loaded, folder, config, ctx);
    });
    return r;
  });

  // Bake ------------------------------------------------------------------------------------
  // qs-bake's atlas for each mesh of a remeshed set: the layout (tiles by area or a grid) and
  // per mesh the baked unit normals and their 8-bit encoding (the PNG's content).
  m.def("_bake", [](const std::shared_ptr<Remesh>& r, const std::shared_ptr<Dissection>& d, int size,
                    const std::string& tiles, const std::string& space, const std::string& green, int gutter,
                    const std::vector<std::string>& formats, int samples, const std::optional<std::string>& out,
                    int threads, const py::object& progress) {
    if (!r || !d) throw qs::UsageError("bake needs a qs.Remesh and the qs.Dissection it was made from");
    if (size < 2 || size > 16384) throw qs::UsageError("size " + std::to_string(size) + ": expected 2 to 16384");
    if (gutter < 0 || gutter > 1024) throw qs::UsageError("gutter " + std::to_string(gutter) + ": expected 0 to 1024");
    if (samples < 0 || samples > 100000000) throw qs::UsageError("samples " + std::to_string(samples) + ": expected 0 to 100000000");
    if (tiles != "area" && tiles != "uniform") throw qs::UsageError("tiles '" + tiles + "': expected area or uniform");
    if (space != "tangent" && space != "object") throw qs::UsageError("space '" + space + "': expected tangent or object");
    if (green != "opengl" && green != "directx") throw qs::UsageError("green '" + green + "': expected opengl or directx");
    const auto& c = r->result.set.connectivity;
    const auto& meshes = d->loaded.meshes;
    if (meshes.size() != r->result.set.positions.size())
      throw qs::InvalidInput("the dissection has " + std::to_string(meshes.size()) + " meshes, the remesh " +
                             std::to_string(r->result.set.positions.size()) + ": not the dissection it was made from");
    for (const auto& dm : meshes)
      if (static_cast<int>(dm.dissection.chart.patches.size()) != c.num_patches)
        throw qs::InvalidInput("the dissection has " + std::to_string(dm.dissection.chart.patches.size()) +
                               " patches, the remesh " + std::to_string(c.num_patches) +
                               ": not the dissection it was made from");
    qs::bake::BakeSetOptions so = qs::bake::bake_set_options(size, tiles, gutter, space, green, samples, formats);
    so.keep_atlases = true;
    qs::bake::BakeSetInput input;
    input.set = &r->result.set;
    input.outputs = r->result.outputs;
    for (const auto& o : r->result.outputs) input.stems.push_back(fs::path(o).stem().string());
    input.dissection = &d->loaded;
    if (out) {
      if (!r->folder)
        throw qs::UsageError("save the remesh first (Remesh.save(folder)): bake.json names the remesh and dissection "
                             "folders, as qs-bake writes it");
      input.remesh_folder = *r->folder;
      input.dissection_folder = *r->dissection_folder;
    }
    const qs::bake::BakePlan plan = qs::bake::plan_bake(input, so);
    const qs::bake::AtlasLayout& layout = plan.layout;
    std::optional<qs::OutputFolder> folder;
    if (out) {
      qs::bake::check_bake_outputs(fs::path(*out), input);
      folder.emplace(*out);
    }
    const qs::bake::BakedSet baked = run_long(progress, threads, [&](const qs::Context& ctx) {
      std::vector<std::unique_ptr<qs::remesh::ChartSampler>> samplers;
      std::vector<const qs::remesh::ChartSampler*> list;
      for (const auto& dm : meshes) {
        samplers.push_back(std::make_unique<qs::remesh::ChartSampler>(dm.dissection.chart, ctx));
        list.push_back(samplers.back().get());
      }
      if (folder) return qs::bake::write_bake_folder(folder->staging(), fs::path(*out), input, list, plan, so, ctx);
      qs::bake::BakedSet set;  // in memory: the same bake, no files, no shading check
      for (size_t i = 0; i < meshes.size(); ++i) {
        qs::bake::BakeOptions mesh_opt = plan.options;
        mesh_opt.original_vertices = meshes[i].input_vertices;
        set.atlases.push_back(qs::bake::bake_normal_map(*list[i], c, r->result.set.positions[i], mesh_opt, ctx).atlas);
      }
      return set;
    });
    if (folder) folder->commit();
    py::list images;
    for (size_t i = 0; i < baked.atlases.size(); ++i) {
      const auto& a = baked.atlases[i];
      py::array_t<float> normals({static_cast<size_t>(a.height), static_cast<size_t>(a.width), size_t{3}});
      std::copy(a.texels.begin(), a.texels.end(), normals.mutable_data());
      const qs::bake::Rgb8Image img = qs::bake::quantize8(a);
      py::array_t<uint8_t> rgb({static_cast<size_t>(img.height), static_cast<size_t>(img.width), size_t{3}});
      std::copy(img.rgb.begin(), img.rgb.end(), rgb.mutable_data());
      py::dict one;
      one["normals"] = normals;
      one["rgb8"] = rgb;
      if (i < baked.meshes.size() && baked.meshes[i].shading) {
        const auto& s = *baked.meshes[i].shading;
        py::dict sh;
        sh["samples"] = s.samples;
        sh["mean_deg_with_map"] = s.mean_with_map;
        sh["p95_deg_with_map"] = s.p95_with_map;
        sh["max_deg_with_map"] = s.max_with_map;
        sh["mean_deg_without_map"] = s.mean_without_map;
        sh["p95_deg_without_map"] = s.p95_without_map;
        sh["max_deg_without_map"] = s.max_without_map;
        one["shading"] = sh;
      }
      images.append(one);
    }
    py::list tiles_out;
    for (int p = 0; p < layout.num_patches; ++p)
      tiles_out.append(py::make_tuple(layout.tile_x(p), layout.tile_y(p), layout.tile_side(p)));
    py::dict result;
    result["images"] = images;
    result["tiles"] = tiles_out;
    result["width"] = layout.width();
    result["height"] = layout.height();
    result["grid"] = layout.grid;
    return result;
  });

  // Morph -----------------------------------------------------------------------------------
  // qs-morph's frames (or one blend) of shapes with one connectivity, aligned onto the path's first.
  m.def("_morph", [](const std::vector<py::object>& shapes, const std::vector<int>& stops, int frames,
                     const std::optional<std::vector<double>>& weights, const std::string& align) {
    std::vector<std::vector<qs::Vec3>> positions;
    for (size_t i = 0; i < shapes.size(); ++i) {
      const std::string what = "positions[" + std::to_string(i) + "]";
      positions.push_back(vertices_from(shapes[i], what.c_str()));
      if (positions.back().size() != positions.front().size())
        invalid(what + ": " + std::to_string(positions.back().size()) + " vertices, positions[0] " +
                std::to_string(positions.front().size()) + ": the shapes must share one connectivity");
    }
    if (positions.size() < 2) throw qs::UsageError("a morph needs at least 2 shapes");
    const qs::morph::Align how = qs::morph::align_from_name(align);
    const int base = weights ? 0 : stops.at(0);
    if (base < 0 || base >= static_cast<int>(positions.size()))
      throw qs::InvalidInput("path: shape " + std::to_string(base) + " is not in [0, " + std::to_string(positions.size()) + ")");
    for (size_t i = 0; i < positions.size(); ++i)
      if (static_cast<int>(i) != base) positions[i] = qs::morph::align_to(positions[i], positions[base], how);
    py::list out;
    auto array = [](const std::vector<qs::Vec3>& p) {
      py::array_t<double> a({p.size(), size_t{3}});
      std::copy(p.empty() ? nullptr : p[0].data(), p.empty() ? nullptr : p[0].data() + 3 * p.size(), a.mutable_data());
      return a;
    };
    if (weights) {
      out.append(array(qs::morph::blend(positions, *weights)));
      return out;
    }
    for (const auto& f : qs::morph::path_frames(static_cast<int>(positions.size()), stops, frames))
      out.append(array(qs::morph::blend(positions, f.weights)));
    return out;
  });

  // qs-morph --glb: the GLB of a remeshed set's morph (base = the path's first shape), the shapes
  // aligned as the frames are; with a bake folder its normal map, UVs and tangents.
  m.def("_morph_glb", [](const std::shared_ptr<Remesh>& r, const std::vector<int>& stops,
                         const std::optional<std::vector<double>>& weights, const std::string& align,
                         const std::string& glb, const std::optional<std::string>& bake) {
    if (!r) throw qs::UsageError("morph: glb needs a qs.Remesh");
    qs::remesh::SemiRegularSet set = r->result.set;
    const int n = static_cast<int>(set.positions.size());
    if (n < 2) throw qs::InvalidInput("the remesh holds " + std::to_string(n) + " shape; a morph needs at least 2");
    for (int s : stops)
      if (s < 0 || s >= n) throw qs::InvalidInput("path: shape " + std::to_string(s) + " is not in [0, " + std::to_string(n) + ")");
    if (stops.empty()) throw qs::InvalidInput("path: no shape");
    if (weights) qs::morph::check_weights(*weights, n);
    std::vector<std::string> names;
    for (const auto& o : r->result.outputs) names.push_back(fs::path(o).stem().string());
    const qs::morph::Align how = qs::morph::align_from_name(align);
    for (int i = 0; i < n; ++i)
      if (i != stops[0]) set.positions[i] = qs::morph::align_to(set.positions[i], set.positions[stops[0]], how);
    std::vector<fs::path> inputs;
    if (r->folder) {
      inputs.push_back(*r->folder / "remesh.json");
      for (const auto& o : r->result.outputs) inputs.push_back(*r->folder / o);
    }
    std::optional<qs::morph::BakedShape> baked;
    if (bake) {
      inputs.push_back(fs::path(*bake) / "bake.json");
      for (const auto& s : names)
        for (const std::string suffix : {".glb", "_normal.png"}) inputs.push_back(fs::path(*bake) / (s + suffix));
    }
    qs::check_not_an_input(glb, inputs, "glb");
    if (bake)
      baked = qs::morph::read_baked_shape(*bake, names[stops[0]], set.connectivity.faces, set.positions[stops[0]]);
    qs::morph::MorphGlbOptions go;
    go.base = stops[0];
    go.path = stops;
    if (weights) go.weights = *weights;
    go.name = "morph";
    const qs::gltf::Mesh mesh = qs::morph::write_morph_glb(glb, set, names, go, baked ? &*baked : nullptr);
    std::vector<std::string> targets;
    for (const auto& t : mesh.targets) targets.push_back(t.name);
    return targets;
  });

  // Merge -----------------------------------------------------------------------------------
  m.def("_merge", [](const std::shared_ptr<Dissection>& d, int a, int b, double sliver_degrees, bool fan, int threads,
                     const py::object& progress) {
    if (!d) throw qs::UsageError("merge needs a qs.Dissection");
    const int n = static_cast<int>(d->loaded.meshes.size());
    if (a < 0 || a >= n || b < 0 || b >= n)
      throw qs::InvalidInput("pair (" + std::to_string(a) + ", " + std::to_string(b) + "): the dissection has " +
                             std::to_string(n) + " meshes");
    if (a == b) throw qs::InvalidInput("pair names mesh " + std::to_string(a) + " twice; merge two different meshes");
    if (!(sliver_degrees >= 0 && sliver_degrees <= 60)) throw qs::UsageError("sliver_degrees: expected 0 to 60");
    qs::merge::MergeOptions options;
    options.sliver_degrees = sliver_degrees;
    options.improve_slivers = !fan;
    const auto& A = d->loaded.meshes[static_cast<size_t>(a)];
    const auto& B = d->loaded.meshes[static_cast<size_t>(b)];
    auto merged = std::make_shared<qs::merge::Merged>(run_long(progress, threads, [&](const qs::Context& ctx) {
      try {
        return qs::merge::merge_charts(A.dissection.chart, B.dissection.chart, options, ctx);
      } catch (const qs::InvalidInput& e) {
        std::string what = e.what();
        for (auto [tag, dm] : {std::pair{"mesh A", &A}, std::pair{"mesh B", &B}})
          if (what.rfind(tag, 0) == 0) what = dm->chart_file + what.substr(6);
        throw qs::InvalidInput(what);
      }
    }));
    py::capsule owner(new std::shared_ptr<qs::merge::Merged>(merged),
                      [](void* p) { delete static_cast<std::shared_ptr<qs::merge::Merged>*>(p); });
    const auto& mg = *merged;
    py::dict out;
    out["faces"] = view<int>(mg.faces.empty() ? nullptr : mg.faces[0].data(), mg.faces.size(), 3, owner);
    py::list pos;
    pos.append(view<double>(mg.positions_a.empty() ? nullptr : mg.positions_a[0].data(), mg.positions_a.size(), 3, owner));
    pos.append(view<double>(mg.positions_b.empty() ? nullptr : mg.positions_b[0].data(), mg.positions_b.size(), 3, owner));
    out["positions"] = pos;
    py::array_t<int> vp(mg.vertex_patch.size());
    std::copy(mg.vertex_patch.begin(), mg.vertex_patch.end(), vp.mutable_data());
    out["vertex_patch"] = vp;
    py::array_t<double> uv({mg.vertex_uv.size(), size_t{2}});
    for (size_t v = 0; v < mg.vertex_uv.size(); ++v) uv.mutable_at(v, 0) = mg.vertex_uv[v].x(), uv.mutable_at(v, 1) = mg.vertex_uv[v].y();
    out["vertex_uv"] = uv;
    const auto& st = mg.stats;
    py::dict stats;
    stats["patches"] = st.patches;
    stats["input_faces"] = py::make_tuple(st.input_faces_a, st.input_faces_b);
    stats["crossings"] = st.crossings;
    stats["coincident_vertices"] = st.coincident_vertices;
    stats["slivers_uv"] = st.slivers_uv;
    stats["slivers"] = py::make_tuple(st.slivers_a, st.slivers_b);
    stats["min_angle_uv"] = st.min_angle_uv;
    stats["min_angle"] = py::make_tuple(st.min_angle_a, st.min_angle_b);
    out["stats"] = stats;
    return out;
  });

  // Correspondence --------------------------------------------------------------------------
  // qs-metro --correspondence: the first mesh against every other, each pair as the tool's JSON
  // object (the same keys and numbers), plus per-vertex errors on request.
  m.def("_correspondence", [](const std::shared_ptr<Dissection>& d, const std::vector<std::string>& maps, long samples,
                              uint64_t seed, int level, bool vertex_errors, int threads, const py::object& progress) {
    if (!d) throw qs::UsageError("correspondence_error needs a qs.Dissection");
    if (samples < 1) throw qs::UsageError("samples must be at least 1");
    if (level < 0 || level > 12) throw qs::UsageError("level " + std::to_string(level) + ": expected 0 to 12");
    const int n = static_cast<int>(d->loaded.meshes.size());
    if (n < 2) throw qs::InvalidInput("the dissection holds 1 mesh; a correspondence needs 2 or more");
    const fs::path folder = d->folder ? *d->folder : fs::path(".");
    const qs::correspondence::TruthFiles files = qs::correspondence::find_truth_files(d->loaded, folder, maps);
    qs::correspondence::MeasureOptions mo;
    mo.samples = samples;
    mo.seed = seed;
    mo.level = level;
    mo.threads = threads;
    mo.vertex_errors = vertex_errors;
    std::optional<qs::correspondence::GroundTruth> truth;
    const std::vector<qs::correspondence::PairMeasure> pairs = run_long(progress, threads, [&](const qs::Context& ctx) {
      truth.emplace(qs::correspondence::load_ground_truth(files));
      return qs::correspondence::measure_dissection(*truth, d->loaded, mo, ctx);
    });
    auto stats = [](const qs::correspondence::ErrorStats& e) {
      py::dict s;
      s["mean_percent"] = e.mean;
      s["median_percent"] = e.median;
      s["p95_percent"] = e.p95;
      s["max_percent"] = e.max;
      return s;
    };
    auto doubles = [](const std::vector<double>& v) {
      py::array_t<double> a(v.size());
      std::copy(v.begin(), v.end(), a.mutable_data());
      return a;
    };
    auto ints = [](const std::vector<int>& v) {
      py::array_t<int> a(v.size());
      std::copy(v.begin(), v.end(), a.mutable_data());
      return a;
    };
    py::list out;
    for (const auto& pm : pairs) {
      py::dict p;
      p["a"] = truth->mesh(pm.a).name;
      p["b"] = truth->mesh(pm.b).name;
      p["samples"] = pm.samples;
      p["diagonal_of_b"] = pm.diagonal;
      p["dissection"] = stats(pm.dissection);
      p["same_patch_share"] = pm.same_patch_share;
      p["corner_distance_mean_percent"] = pm.corner_mean;
      p["corner_distance_max_percent"] = pm.corner_max;
      py::dict dist;
      dist["on"] = pm.distortion_on_b ? "b" : "a";
      dist["dissection_mean"] = pm.distortion;
      dist["dissection_median"] = pm.distortion_median;
      dist["dissection_folded_faces"] = pm.distortion_folded;
      dist["truth_mean"] = pm.truth_distortion;
      dist["truth_median"] = pm.truth_distortion_median;
      dist["truth_folded_faces"] = pm.truth_distortion_folded;
      p["distortion"] = dist;
      p["baseline"] = stats(pm.baseline);
      p["baseline_landmarks"] = pm.baseline_landmarks;
      p["truth_tolerance_percent"] = pm.truth_tolerance;
      p["truth_tolerance_mean_percent"] = pm.truth_tolerance_mean;
      if (pm.level > 0) p["remesh_alone"] = stats(pm.remesh);
      if (vertex_errors) {
        p["vertex_error"] = doubles(pm.vertex_error);
        p["vertex_baseline_error"] = doubles(pm.vertex_baseline_error);
        p["vertex_patch"] = ints(pm.vertex_patch);
        p["vertex_exact_patch"] = ints(pm.vertex_exact_patch);
      }
      out.append(p);
    }
    return out;
  });

  // Metro -----------------------------------------------------------------------------------
  m.def("_metro", [](const Mesh& a, const Mesh& b, long samples, bool vertices, uint64_t seed, int threads,
                     const py::object& progress) {
    if (samples < 0) throw qs::UsageError("samples must be at least 0 (0: the automatic count)");
    qs::metro::MetroOptions o;
    o.face_samples = samples;
    o.sample_vertices = vertices;
    o.seed = seed;
    const qs::metro::MetroResult r = run_long(progress, threads, [&](const qs::Context& ctx) {
      try {
        return qs::metro::metro(a.read.mesh, b.read.mesh, o, ctx);
      } catch (const qs::InvalidInput& e) {  // the library names the meshes "A" and "B"
        throw qs::InvalidInput(std::string(e.what()) + " (A = " + a.name + ", B = " + b.name + ")");
      }
    });
    auto side = [](const qs::metro::OneSided& s) {
      py::dict d;
      d["mean"] = s.mean;
      d["rms"] = s.rms;
      d["max"] = s.max;
      d["max_at"] = py::make_tuple(s.max_at.x(), s.max_at.y(), s.max_at.z());
      d["samples"] = s.samples;
      d["vertex_samples"] = s.vertex_samples;
      return d;
    };
    py::dict out;
    out["mean"] = r.mean;
    out["rms"] = r.rms;
    out["max"] = r.max;
    out["diagonal"] = r.diagonal;
    out["area_a"] = r.area_a;
    out["area_b"] = r.area_b;
    out["a_to_b"] = side(r.a_to_b);
    out["b_to_a"] = side(r.b_to_a);
    return out;
  });
}
