//                       pd-fem: deal.II reference solutions
//
// Compile with: cmake --preset default && cmake --build build --target pd-fem
//
// Sample runs:  build/bin/pd-fem fem_reference/prm/clamped-beam.prm
//               build/bin/pd-fem fem_reference/prm/cantilever.prm --coarse
//               build/bin/pd-fem fem_reference/prm/plate-3clamped.prm -o /tmp/plate
//               build/bin/pd-fem fem_reference/prm/cantilever.prm --coarse
//                   --check fem_reference/reference/cantilever.json   (one line)
//               build/bin/pd-fem --print-parameters     (all entries, documented)
//
// Description:  small-strain linear elasticity of a rectangular block
//               Ω = [0,Lx] x [0,Ly] x [0,Lz] of an isotropic material (E, ν),
//
//                   -div σ(u) = 0                 in Ω,
//                   σ(u) = λ tr ε(u) I + 2 μ ε(u),   ε(u) = (∇u + ∇u^T)/2,
//                   u = 0                         on the clamped faces,
//                   σ n = (0, 0, -q)              on the top face z = Lz,
//                   σ n = 0                       on all other faces,
//
//               or (Geometry/Dimension = 2) of the rectangle [0,Lx] x [0,Hy]
//               of out-of-plane thickness t, loaded by σ n = (0, -q) on the
//               top edge y = Hy: plane strain (ε_zz = 0, the same λ, μ) or
//               plane stress (σ_zz = 0, λ* = 2λμ/(λ+2μ) for λ).
//
//               It provides the converged continuum reference for the
//               peridynamics verification cases (Miranda et al. 2019,
//               §5.1.1 and §5.1.2), all with E = 20 GPa, ν = 0.25:
//
//               clamped-beam.prm   L x b x h = 3.5 x 0.3 x 0.4 m, faces x=0
//                                  and x=L clamped, p = 10 kN/m (q = p/b);
//                                  quantity: midspan deflection.
//               cantilever.prm     same beam, only x=0 clamped; tip
//                                  deflection at x=L.
//               plate-3clamped.prm 4 x 3 x 0.25 m plate, faces x=0, x=4 and
//                                  y=0 clamped, y=3 free, q = 10 kN/m^2;
//                                  free-edge midpoint and centre deflection.
//
//               and their 2D counterparts (L x h = 3.5 x 0.4 m, t = 0.3 m):
//               cantilever-2d.prm  plane stress, ν = 1/3; tip deflection.
//               clamped-beam-2d.prm plane strain, ν = 0.25; midspan.
//
//                        z (gravity -z)      q  q  q  q  q  q  q
//                        |  y                |  |  |  |  |  |  |
//                        | /              +--v--v--v--v--v--v--v--+
//                        |/             //|                      /|
//                        +---- x       // +---------------------+ |  Lz
//                                  clamped|                     | +
//                                  face  //|                    |/  Ly
//                                  x = 0  +---------------------+
//                                                  Lx
//
//               Q_p elements (FESystem(FE_Q(p), dim), p = 2 by default) on a
//               sequence of uniformly refined box meshes; CG preconditioned
//               with Trilinos ML AMG using the rigid-body modes. For every
//               level the deflection (-u_z, 2D: -u_y, positive downward) at the
//               requested points is reported, and Richardson extrapolation
//               of the last three levels estimates the discretisation error.
//               The summary compares with Euler-Bernoulli / Timoshenko beam
//               theory or a Kirchhoff plate series solution.
//
// Outputs (in -o DIR, default fem_reference/out/NAME):
//   summary.json    parameters, per-level values/times/iterations,
//                   extrapolation, theory, notes
//   NAME.csv        deflection along each "Sample lines" entry
//   solution.vtu    finest displacement field (ParaView)
//   parameters.prm  the parameters actually used
//
// Threads: assembly uses all cores through deal.II's WorkStream; set
// DEAL_II_NUM_THREADS to limit them. No MPI parallelism (one process).

#include "elastic_reference.h"
#include "kirchhoff_plate.h"
#include "libpd/core/blas.hpp"
#include "scene_reference.h"

#include <boost/property_tree/json_parser.hpp>
#include <boost/property_tree/ptree.hpp>
#include <cmath>
#include <cstdio>
#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/utilities.h>
#include <iostream>
#include <sstream>
#include <string>

namespace {
const char* const usage_text =
    "usage: pd-fem PRMFILE [-o DIR] [--levels N] [--coarse] [--check REFERENCE.json]\n"
    "       pd-fem --scene SCENE.yaml [-o DIR] [--levels N] [--coarse]\n"
    "       pd-fem --print-parameters | --kirchhoff-selftest | --richardson-selftest | --help\n"
    "\n"
    "Solves linear elasticity (3D, or 2D plane stress / plane strain) with deal.II\n"
    "on a sequence of refined meshes\n"
    "and writes summary.json, deflection lines (CSV) and solution.vtu.\n"
    "\n"
    "  PRMFILE            deal.II parameter file (see fem_reference/prm/)\n"
    "  --scene FILE       instead: the linear-elastic problem of a libpd scene\n"
    "                     (bodies, supports, loads, probes as PD reads them);\n"
    "                     writes DIR/fe.json (default fem_reference/out/STEM)\n"
    "  --gmsh             (--scene) mesh with Gmsh even if every shape is a box\n"
    "  -o DIR             output directory (default fem_reference/out/NAME,\n"
    "                     relative to the current directory)\n"
    "  --levels N         number of refinement levels (overrides the file)\n"
    "  --coarse           use the 'Coarse levels' of the file (quick run)\n"
    "  --check FILE       compare with a stored reference summary: the finest\n"
    "                     value must agree with the reference value within the\n"
    "                     run's estimated discretisation error, and every level\n"
    "                     present in both must reproduce the stored value\n"
    "                     (relative 1e-6); exit code 2 on failure\n"
    "  --print-parameters print every parameter with its documentation\n"
    "  --kirchhoff-selftest  verify the Kirchhoff plate series solver\n"
    "  --richardson-selftest verify the Richardson extrapolation (equal and\n"
    "                     unequal ratios between the levels' mesh sizes)\n"
    "  --help             this text\n";

struct Arguments {
  std::string prm_file, output_dir, check_file, scene_file;
  int levels = -1;
  bool coarse = false;
  bool gmsh = false;
};

// Compare a run with a stored reference summary.json. Returns true if all
// checks pass and prints one line per check.
bool check_against_reference(const pdfem::RunSummary& run, const std::string& reference_file) {
  namespace pt = boost::property_tree;
  pt::ptree ref;
  try {
    pt::read_json(reference_file, ref);
  } catch (const std::exception& e) {
    throw std::runtime_error("cannot read reference file '" + reference_file + "': " + e.what());
  }
  using path = pt::ptree::path_type;
  bool ok = true;
  for (const auto& q : run.quantities) {
    const auto node = ref.get_child_optional(path("quantities/" + q.name, '/'));
    if (!node) {
      std::printf("CHECK FAIL %s: quantity missing in %s\n", q.name.c_str(),
                  reference_file.c_str());
      ok = false;
      continue;
    }
    const double ref_value = node->get<double>("value");
    const double ref_error = node->get<double>("error_estimate");
    // The reference is converged to ~0.1 %; the run under test (e.g. the
    // coarse levels) is accurate to its own Richardson estimate. Their
    // difference must be explained by the two estimates (1.5x safety on
    // the run's estimate, which comes from coarse levels).
    const double tol = 1.5 * q.richardson.error_estimate + ref_error + 1e-9 * std::abs(ref_value);
    const double diff = std::abs(q.finest - ref_value);
    const bool pass = diff <= tol;
    ok = ok && pass;
    std::printf("CHECK %s %-14s value %.8e  reference %.8e  |diff| %.3e"
                " (%.3f %%)  allowed %.3e  (estimated error of this run "
                "%.3e, of the reference %.3e)\n",
                pass ? "PASS" : "FAIL", q.name.c_str(), q.finest, ref_value, diff,
                100. * diff / std::abs(ref_value), tol, q.richardson.error_estimate, ref_error);

    // Level-by-level reproduction of the stored values.
    unsigned int matched = 0;
    for (const auto& level : run.levels)
      for (const auto& rl : ref.get_child("levels"))
        if (rl.second.get<unsigned long>("dofs") == level.dofs &&
            rl.second.get<unsigned int>("cells") == level.cells) {
          const double stored = rl.second.get<double>(path("deflection/" + q.name, '/'));
          const double value = level.deflection.at(q.name);
          const double rel = std::abs(value - stored) / std::abs(stored);
          const bool same = rel <= 1e-6;
          ok = ok && same;
          ++matched;
          std::printf("CHECK %s %-14s level %u (%lu dofs) value %.10e "
                      "stored %.10e  rel. diff %.2e (allowed 1e-6)\n",
                      same ? "PASS" : "FAIL", q.name.c_str(), level.level,
                      static_cast<unsigned long>(level.dofs), value, stored, rel);
        }
    if (matched == 0) {
      std::printf("CHECK FAIL %s: no level of this run is stored in "
                  "the reference (different mesh or element?)\n",
                  q.name.c_str());
      ok = false;
    }
  }
  return ok;
}
// pd-fem --scene: the FE reference of a libpd scene (scene_reference.h).
int run_scene(const Arguments& args) {
  if (!args.prm_file.empty())
    throw std::runtime_error("--scene and a parameter file exclude each other\n" +
                             std::string(usage_text));
  if (!args.check_file.empty())
    throw std::runtime_error("--check applies to parameter files only");
  const pdfem::SceneProblem problem = pdfem::read_scene_problem(args.scene_file);
  pdfem::SceneOptions options;
  options.levels = args.levels > 0 ? static_cast<unsigned int>(args.levels) : 0;
  options.coarse = args.coarse;
  options.gmsh = args.gmsh;
  options.output_directory = args.output_dir.empty()
                                 ? std::filesystem::path("fem_reference") / "out" /
                                       std::filesystem::path(args.scene_file).stem()
                                 : std::filesystem::path(args.output_dir);
  pdfem::solve_scene(problem, options);
  std::printf("%s: output in %s\n", args.scene_file.c_str(),
              (options.output_directory / "fe.json").string().c_str());
  return 0;
}
// pd-fem PARAMETER_FILE: the reference solution of a parameter file, with --check against a
// stored one (2 if it fails).
int run_parameter_file(const Arguments& args, const std::string& command_line) {
  using namespace dealii;
  ParameterHandler prm;
  pdfem::Parameters::declare(prm);
  // Throws with the file name and line number on any bad entry.
  prm.parse_input(args.prm_file);
  pdfem::Parameters parameters;
  parameters.parse(prm);

  unsigned int n_levels = args.coarse ? parameters.n_coarse_levels : parameters.n_levels;
  if (args.levels > 0)
    n_levels = static_cast<unsigned int>(args.levels);
  const std::filesystem::path out_dir =
      args.output_dir.empty() ? std::filesystem::path("fem_reference") / "out" / parameters.name
                              : std::filesystem::path(args.output_dir);

  std::ostringstream prm_json, prm_text;
  prm.print_parameters(prm_json, ParameterHandler::ShortJSON);
  prm.print_parameters(prm_text, ParameterHandler::ShortPRM);

  const pdfem::RunSummary summary = pdfem::solve_reference(
      parameters, n_levels, out_dir, command_line, prm_json.str(), prm_text.str());

  for (const auto& q : summary.quantities) {
    std::printf("%s: %-14s deflection %.8e m (finest), extrapolated "
                "%.8e m, observed order %s, estimated error %s\n",
                parameters.name.c_str(), q.name.c_str(), q.finest, q.richardson.extrapolated,
                q.richardson.order ? std::to_string(*q.richardson.order).c_str() : "n/a",
                q.richardson.valid
                    ? (std::to_string(100. * q.richardson.relative_error) + " %").c_str()
                    : "n/a (needs 3 levels in the asymptotic range)");
  }
  std::printf("%s: wall time %.2f s; output in %s\n", parameters.name.c_str(), summary.wall_time,
              out_dir.string().c_str());

  if (!args.check_file.empty()) {
    if (!check_against_reference(summary, args.check_file)) {
      std::fprintf(stderr, "pd-fem: check against %s FAILED\n", args.check_file.c_str());
      return 2;
    }
    std::printf("check against %s passed\n", args.check_file.c_str());
  }
  return 0;
}
} // namespace

namespace {
// Before the libraries' initialisers (deal.II, Trilinos, PETSc, Open MPI): a SIGTERM or Ctrl-C
// that arrived while the start-up restart had them blocked ends pd-fem now, not after loading.
void take_back_stop_signals(int /*argc*/, char** /*argv*/, char** /*envp*/) {
  pd::take_back_stop_signals_after_restart();
}
// NOLINTNEXTLINE: the ELF hook that runs before every shared library's initialiser.
[[gnu::section(".preinit_array"),
  gnu::used]] void (*const take_back_early)(int, char**, char**) = take_back_stop_signals;
} // namespace

int main(int argc, char** argv) {
  using namespace dealii;
  // The direct solves run CHOLMOD on OpenBLAS: its fast kernels on CPUs it does not recognise,
  // and passive OpenMP waiting on a busy machine (libpd/core/blas.hpp).
  pd::restart_with_process_settings(argv);
  try {
    // Trilinos (Epetra) matrices need MPI to be initialised; one process,
    // threads for the assembly (all cores unless DEAL_II_NUM_THREADS).
    Utilities::MPI::MPI_InitFinalize mpi(argc, argv, numbers::invalid_unsigned_int);
    if (Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD) != 1)
      throw std::runtime_error("pd-fem runs as a single MPI process");

    Arguments args;
    std::string command_line = "pd-fem";
    for (int i = 1; i < argc; ++i)
      command_line += std::string(" ") + argv[i];

    auto need_value = [&](int& i) -> std::string {
      if (i + 1 >= argc)
        throw std::runtime_error(std::string("option ") + argv[i] + " needs a value\n" +
                                 usage_text);
      return argv[++i];
    };
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--help" || a == "-h") {
        std::cout << usage_text;
        return 0;
      } else if (a == "--print-parameters") {
        ParameterHandler prm;
        pdfem::Parameters::declare(prm);
        prm.print_parameters(std::cout, ParameterHandler::PRM);
        return 0;
      } else if (a == "--kirchhoff-selftest")
        return pdfem::kirchhoff_selftest() ? 0 : 2;
      else if (a == "--richardson-selftest")
        return pdfem::richardson_selftest() ? 0 : 2;
      else if (a == "-o")
        args.output_dir = need_value(i);
      else if (a == "--levels") {
        const std::string v = need_value(i);
        args.levels = Utilities::string_to_int(v);
        if (args.levels < 1 || args.levels > 8)
          throw std::runtime_error("--levels must be between 1 and 8");
      } else if (a == "--coarse")
        args.coarse = true;
      else if (a == "--check")
        args.check_file = need_value(i);
      else if (a == "--scene")
        args.scene_file = need_value(i);
      else if (a == "--gmsh")
        args.gmsh = true;
      else if (!a.empty() && a[0] == '-')
        throw std::runtime_error("unknown option '" + a + "'\n" + usage_text);
      else if (args.prm_file.empty())
        args.prm_file = a;
      else
        throw std::runtime_error("more than one parameter file given\n" + std::string(usage_text));
    }
    if (!args.scene_file.empty())
      return run_scene(args);
    if (args.prm_file.empty())
      throw std::runtime_error(std::string("no parameter file given\n") + usage_text);

    return run_parameter_file(args, command_line);
  } catch (const pd::SceneError& e) {
    // Already "FILE:LINE:COLUMN: error: WHAT" with a hint.
    std::cerr << e.what() << std::endl;
    return 1;
  } catch (const dealii::ExceptionBase& e) {
    // deal.II exceptions (e.g. a bad .prm entry): print the message
    // ("Line <7> of file <x.prm>: ..."), not the source location and
    // stack trace of the library.
    std::cerr << "pd-fem: error: ";
    e.print_info(std::cerr);
    std::cerr << std::endl;
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "pd-fem: error: " << e.what() << std::endl;
    return 1;
  } catch (...) {
    std::cerr << "pd-fem: error: unknown exception" << std::endl;
    return 1;
  }
  return 0;
}
