// The case functions registered in verification.cpp; one file per case under cases/.
#pragma once

#include "libpd/io/scene.hpp"
#include "verification.hpp"

namespace pd::verification {

Json run_bond_count(const Context& ctx);
Json run_bar_vibration(const Context& ctx);
Json run_bar_energy(const Context& ctx);
Json run_block_tension(const Context& ctx);
Json run_block_tension_thin(const Context& ctx);
Json run_patch_test(const Context& ctx);
Json run_block_tension_corrections(const Context& ctx);
Json run_clamped_beam(const Context& ctx);
Json run_cantilever(const Context& ctx);
Json run_plate(const Context& ctx);
Json run_clamped_beam_fast(const Context& ctx);
Json run_cantilever_fast(const Context& ctx);
Json run_plate_fast(const Context& ctx);
Json run_clamped_beam_sweep(const Context& ctx);
Json run_cantilever_sweep(const Context& ctx);
Json run_plate_sweep(const Context& ctx);
Json run_cantilever_2d(const Context& ctx);
Json run_clamped_beam_2d(const Context& ctx);
Json run_cantilever_2d_fast(const Context& ctx);
Json run_clamped_beam_2d_fast(const Context& ctx);
Json run_cantilever_2d_sweep(const Context& ctx);
Json run_clamped_beam_2d_sweep(const Context& ctx);
/// A structure described by verification/cases/NAME.case.yaml: at the scene's resolution
/// (`fast`: the case's CI spacing, regression and gates, no relaxation rerun), or its sweep.
Json run_structure_case(const Context& ctx, const std::string& case_name, bool fast);
Json run_structure_sweep_case(const Context& ctx, const std::string& case_name);
/// A structural scene at another spacing (CI variants, sweeps, `pd compare quasistatic --quick`):
/// a load on the top particle layer stays on the top layer.
void set_spacing(Scene& scene, double spacing);
Json run_rc_beam(const Context& ctx);
Json run_compression_cube(const Context& ctx);
Json run_rc_beam_static(const Context& ctx);
Json run_compression_cube_static(const Context& ctx);
Json run_symmetry_half_full(const Context& ctx);
Json run_crack_opening(const Context& ctx);
Json run_fracture_stop(const Context& ctx);
Json run_poisson_control(const Context& ctx);
Json run_poisson_control_full(const Context& ctx);
Json run_elliptic_disk(const Context& ctx);
Json run_elliptic_disk_convergence(const Context& ctx);
Json run_elliptic_disk_saving(const Context& ctx);
Json run_elliptic_disk_regular(const Context& ctx);
Json run_griffith(const Context& ctx);
Json run_griffith_full(const Context& ctx);
Json run_griffith_boundary(const Context& ctx);
Json run_griffith_resolution(const Context& ctx);
Json run_griffith_table1(const Context& ctx);

} // namespace pd::verification
