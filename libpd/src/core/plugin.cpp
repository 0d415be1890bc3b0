// Loading plug-ins (core/plugin.hpp).
#include "libpd/core/plugin.hpp"

#include <algorithm>
#include <cstdlib>
#include <dlfcn.h>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace pd {

namespace {

std::vector<std::string> plugin_folders() {
  std::vector<std::string> folders;
  if (const char* env = std::getenv("LIBPD_PLUGIN_DIR"); env && *env) {
    folders.emplace_back(env);
  }
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    folders.push_back((exe.parent_path() / ".." / "lib" / "libpd").lexically_normal().string());
  }
#ifdef LIBPD_PLUGIN_INSTALL_DIR
  folders.emplace_back(LIBPD_PLUGIN_INSTALL_DIR);
#endif
#ifdef LIBPD_PLUGIN_BUILD_DIR
  folders.emplace_back(LIBPD_PLUGIN_BUILD_DIR);
#endif
  // The build tree's programs find the build folder by their own path too: try each once.
  std::vector<std::string> unique;
  for (const std::string& f : folders) {
    if (std::find(unique.begin(), unique.end(), f) == unique.end()) {
      unique.push_back(f);
    }
  }
  return unique;
}

/// The table from the module at `path`, or null with the reason in `why`. A module that loads
/// but does not fit is closed again.
const void* try_load(const PluginSpec& spec, const std::string& path, std::string& why) {
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) {
    const char* error = dlerror();
    why = error ? error : path + ": dlopen failed"; // dlerror() names the file
    return nullptr;
  }
  using Entry = const void* (*)();
  dlerror();
  const auto entry = reinterpret_cast<Entry>(dlsym(handle, spec.entry));
  if (!entry) {
    const char* error = dlerror();
    why = error ? error : path + ": no symbol " + spec.entry;
    dlclose(handle);
    return nullptr;
  }
  const void* table = entry();
  const std::uint32_t version = table ? *static_cast<const std::uint32_t*>(table) : 0;
  if (version != spec.version) {
    why = path + ": interface version " + std::to_string(version) + ", this libpd needs " +
          std::to_string(spec.version) + " (a plug-in from another build of libpd)";
    dlclose(handle);
    return nullptr;
  }
  return table; // the module stays open: its state (Gmsh, PETSc) lives as long as the process
}

} // namespace

const void* load_plugin(const PluginSpec& spec) {
  static std::mutex mutex;
  static std::map<std::string, const void*> loaded;
  const std::lock_guard<std::mutex> lock(mutex);
  if (const auto found = loaded.find(spec.module); found != loaded.end()) {
    return found->second;
  }
  std::string tried;
  for (const std::string& folder : plugin_folders()) {
    const std::string path = (std::filesystem::path(folder) / spec.module).string();
    std::string why;
    if (const void* table = try_load(spec, path, why)) {
      loaded.emplace(spec.module, table);
      return table;
    }
    tried += (tried.empty() ? "" : "; ") + why;
  }
  throw PluginError(std::string(spec.feature) + " needs the plug-in " + spec.module +
                    ", which could not be loaded (set LIBPD_PLUGIN_DIR to the folder holding "
                    "it); tried " +
                    tried);
}

} // namespace pd
