// Assigning particles to ranks with Zoltan (distribution.hpp). Built with Zoltan and MPI
// (LIBPD_HAVE_ZOLTAN); without them one rank owns everything.
#include "libpd/discretisation/distribution.hpp"

#include <fmt/format.h>
#include <stdexcept>

#ifdef LIBPD_HAVE_ZOLTAN
#include <mpi.h>
#include <zoltan.h>
#endif

namespace pd {

#ifdef LIBPD_HAVE_ZOLTAN

namespace {

/// The particles this rank hands to Zoltan: a contiguous block of global indices. Zoltan moves
/// them to their parts; the answer depends on the model and the rank count only.
struct ZoltanInput {
  const Model* model = nullptr;
  std::size_t first = 0;
  std::size_t count = 0;
};

int object_count(void* data, int* ierr) {
  *ierr = ZOLTAN_OK;
  return static_cast<int>(static_cast<ZoltanInput*>(data)->count);
}

void object_list(void* data, int /*gid_entries*/, int /*lid_entries*/, ZOLTAN_ID_PTR gids,
                 ZOLTAN_ID_PTR lids, int /*weight_dim*/, float* /*weights*/, int* ierr) {
  const auto* in = static_cast<ZoltanInput*>(data);
  for (std::size_t k = 0; k < in->count; ++k) {
    gids[k] = static_cast<ZOLTAN_ID_TYPE>(in->first + k);
    lids[k] = static_cast<ZOLTAN_ID_TYPE>(k);
  }
  *ierr = ZOLTAN_OK;
}

int geometry_dimension(void* data, int* ierr) {
  *ierr = ZOLTAN_OK;
  return static_cast<ZoltanInput*>(data)->model->spec.dimension.dim;
}

void geometry(void* data, int /*gid_entries*/, int /*lid_entries*/, int count,
              ZOLTAN_ID_PTR /*gids*/, ZOLTAN_ID_PTR lids, int dim, double* coordinates, int* ierr) {
  const auto* in = static_cast<ZoltanInput*>(data);
  for (int k = 0; k < count; ++k) {
    const Vec3& x = in->model->particles.position[in->first + lids[k]];
    for (int c = 0; c < dim; ++c) {
      coordinates[k * dim + c] = x[static_cast<std::size_t>(c)];
    }
  }
  *ierr = ZOLTAN_OK;
}

void edge_counts(void* data, int /*gid_entries*/, int /*lid_entries*/, int count,
                 ZOLTAN_ID_PTR /*gids*/, ZOLTAN_ID_PTR lids, int* edges, int* ierr) {
  const auto* in = static_cast<ZoltanInput*>(data);
  for (int k = 0; k < count; ++k) {
    edges[k] = static_cast<int>(in->model->family.family_size(in->first + lids[k]));
  }
  *ierr = ZOLTAN_OK;
}

/// Zoltan's edge callback needs the rank holding each neighbour at input: the block owner.
struct BlockRule {
  std::size_t n = 0;
  int ranks = 1;
  std::size_t first(int r) const {
    return n * static_cast<std::size_t>(r) / static_cast<std::size_t>(ranks);
  }
  int rank_of(std::size_t i) const {
    int r = static_cast<int>(i * static_cast<std::size_t>(ranks) / n);
    while (r + 1 < ranks && i >= first(r + 1)) {
      ++r;
    }
    while (r > 0 && i < first(r)) {
      --r;
    }
    return r;
  }
};

struct GraphInput : ZoltanInput {
  BlockRule blocks;
};

void graph_edge_lists(void* data, int /*gid_entries*/, int /*lid_entries*/, int count,
                      ZOLTAN_ID_PTR /*gids*/, ZOLTAN_ID_PTR lids, int* /*counts*/,
                      ZOLTAN_ID_PTR neighbours, int* neighbour_ranks, int /*weight_dim*/,
                      float* /*weights*/, int* ierr) {
  const auto* in = static_cast<GraphInput*>(data);
  const BondFamily& f = in->model->family;
  std::size_t out = 0;
  for (int k = 0; k < count; ++k) {
    const std::size_t i = in->first + lids[k];
    for (std::size_t b = f.offsets[i]; b < f.offsets[i + 1]; ++b) {
      neighbours[out] = f.neighbour[b];
      neighbour_ranks[out] = in->blocks.rank_of(f.neighbour[b]);
      ++out;
    }
  }
  *ierr = ZOLTAN_OK;
}

void set(Zoltan_Struct* zz, const char* name, const std::string& value) {
  if (Zoltan_Set_Param(zz, name, value.c_str()) != ZOLTAN_OK) {
    throw std::runtime_error(fmt::format("Zoltan refused parameter {} = {}", name, value));
  }
}

} // namespace

std::vector<std::int32_t> partition_particles(const Model& global, const Communicator& comm,
                                              PartitionMethod method) {
  const std::size_t n = global.size();
  std::vector<std::int32_t> owner(n, 0);
  if (comm.size() == 1 || comm.native() == nullptr) {
    return owner;
  }
  static const bool initialised = [] {
    float version = 0;
    return Zoltan_Initialize(0, nullptr, &version) == ZOLTAN_OK;
  }();
  if (!initialised) {
    throw std::runtime_error("Zoltan_Initialize failed");
  }
  const MPI_Comm mpi = *static_cast<const MPI_Comm*>(comm.native());
  GraphInput in;
  in.model = &global;
  in.blocks = {n, comm.size()};
  in.first = in.blocks.first(comm.rank());
  in.count = in.blocks.first(comm.rank() + 1) - in.first;

  Zoltan_Struct* zz = Zoltan_Create(mpi);
  set(zz, "DEBUG_LEVEL", "0");
  set(zz, "NUM_GID_ENTRIES", "1");
  set(zz, "NUM_LID_ENTRIES", "1");
  set(zz, "RETURN_LISTS", "EXPORT");
  set(zz, "OBJ_WEIGHT_DIM", "0");
  set(zz, "EDGE_WEIGHT_DIM", "0");
  Zoltan_Set_Num_Obj_Fn(zz, object_count, &in);
  Zoltan_Set_Obj_List_Fn(zz, object_list, &in);
  if (method == PartitionMethod::rcb) {
    set(zz, "LB_METHOD", "RCB");
    Zoltan_Set_Num_Geom_Fn(zz, geometry_dimension, &in);
    Zoltan_Set_Geom_Multi_Fn(zz, geometry, &in);
  } else {
    set(zz, "LB_METHOD", "GRAPH");
    set(zz, "GRAPH_PACKAGE", "SCOTCH");
    set(zz, "LB_APPROACH", "PARTITION");
    Zoltan_Set_Num_Edges_Multi_Fn(zz, edge_counts, &in);
    Zoltan_Set_Edge_List_Multi_Fn(zz, graph_edge_lists, &in);
  }
  int changes = 0, gid_entries = 0, lid_entries = 0, imports = 0, exports = 0;
  ZOLTAN_ID_PTR import_gids = nullptr, import_lids = nullptr, export_gids = nullptr,
                export_lids = nullptr;
  int *import_procs = nullptr, *import_parts = nullptr, *export_procs = nullptr,
      *export_parts = nullptr;
  const int rc = Zoltan_LB_Partition(
      zz, &changes, &gid_entries, &lid_entries, &imports, &import_gids, &import_lids, &import_procs,
      &import_parts, &exports, &export_gids, &export_lids, &export_procs, &export_parts);
  if (rc != ZOLTAN_OK) {
    Zoltan_Destroy(&zz);
    throw std::runtime_error(
        fmt::format("Zoltan could not partition the model ({}, code {})", name_of(method), rc));
  }
  std::vector<std::int32_t> mine(n, -1);
  for (std::size_t k = 0; k < in.count; ++k) {
    mine[in.first + k] = comm.rank();
  }
  for (int k = 0; k < exports; ++k) {
    mine[export_gids[k]] = export_parts[k];
  }
  Zoltan_LB_Free_Part(&import_gids, &import_lids, &import_procs, &import_parts);
  Zoltan_LB_Free_Part(&export_gids, &export_lids, &export_procs, &export_parts);
  Zoltan_Destroy(&zz);
  comm.max(mine); // each particle was listed by exactly one rank
  return mine;
}

#else

std::vector<std::int32_t> partition_particles(const Model& global, const Communicator& comm,
                                              PartitionMethod /*method*/) {
  if (comm.size() > 1) {
    throw std::runtime_error("libpd was built without Zoltan: it cannot split a model over ranks");
  }
  return std::vector<std::int32_t>(global.size(), 0);
}

#endif

} // namespace pd
