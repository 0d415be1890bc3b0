// Plug-ins: optional features whose libraries are heavy to load (Gmsh with OpenCASCADE, PETSc)
// live in modules that libpd opens on first use, so a run that does not use them does not pay
// for them at start-up.
//
// A plug-in is a shared module `libpd_NAME.so` with one extern "C" function returning a table
// of plain function pointers whose first member is the table's version (a std::uint32_t). The
// table's layout is defined in one header that libpd and the plug-in both include; libpd refuses
// a table of another version, so a plug-in built from other sources cannot be called silently.
//
// The module is looked for, in this order, in
//   1. the folder named by the environment variable LIBPD_PLUGIN_DIR,
//   2. ../lib/libpd relative to the folder of the running executable (an installed tree),
//   3. the folder libpd is installed to (lib/libpd under the install prefix),
//   4. the build tree's lib/libpd (the folder the build puts the modules in).
#pragma once

#include <cstdint>
#include <stdexcept>

namespace pd {

/// A plug-in that could not be loaded: its message names the feature, every path tried and why
/// each failed (the dynamic loader's words).
class PluginError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

struct PluginSpec {
  const char* feature; ///< for messages, e.g. "bodies from meshes and geometry files (Gmsh)"
  const char* module;  ///< the file name, e.g. "libpd_gmsh.so"
  const char* entry;   ///< the extern "C" function returning the table
  std::uint32_t version;
};

/// The plug-in's function table, loaded on the first call and kept for the life of the process;
/// PluginError if no folder holds a module that loads, has the entry point and has the version.
/// Thread-safe.
const void* load_plugin(const PluginSpec& spec);

} // namespace pd
