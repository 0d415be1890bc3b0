// The `effects` list and the `model` section: what the bond model simulates and how its bonds are
// corrected.
#include "bind.hpp"
#include "sections.hpp"

namespace pd::scene {

namespace {

/// The model options as scene files default them. The corrections default to the pair picked from
/// the block-tension measurements (tensor + moment: +0.35 % elongation, +0.59 % lateral
/// contraction); ModelSpec's own default stays the bare model (none + none) for code that
/// assembles models directly.
struct SceneModelOptions {
  StretchKind stretch = EffectSet{}.stretch;
  SurfaceCorrection surface_correction = SurfaceCorrection::tensor;
  VolumeCorrection volume_correction = VolumeCorrection::moment;
  /// `copy` stays the default only until issue 14's default surface treatment lands: the shipped
  /// structural scenes' correction pairs were calibrated against it (mirror_constraints.hpp).
  MirrorCoupling mirror_coupling = MirrorCoupling::copy;
};

constexpr Key model_keys[] = {
    {.name = "stretch",
     .type = Type::choice,
     .doc = "stretch measure (exact eq. 6, modified eq. 17, fast: no square root)",
     .choices = enum_words<StretchKind>,
     .bind = field_with_default<&SceneModelOptions::stretch>()},
    {.name = "surface_correction",
     .type = Type::choice,
     .doc = "bond stiffness correction near free surfaces",
     .choices = enum_words<SurfaceCorrection>,
     .bind = field_with_default<&SceneModelOptions::surface_correction>()},
    {.name = "volume_correction",
     .type = Type::choice,
     .doc = "bond quadrature weights: partial volume of cut cells (linear, exact) or "
            "moment-matched lattice weights (moment)",
     .choices = enum_words<VolumeCorrection>,
     .bind = field_with_default<&SceneModelOptions::volume_correction>()},
    {.name = "mirror_coupling",
     .type = Type::choice,
     .doc = "mirror supports: copy (support particles copy their images' displacements, one-sided, "
            "not energy-conserving; the default while the structural scenes' correction pairs are "
            "calibrated on it) or consistent (forces sent back to the images: symmetric, "
            "energy-conserving)",
     .choices = enum_words<MirrorCoupling>,
     .bind = field_with_default<&SceneModelOptions::mirror_coupling>()},
};

} // namespace

constinit const Section model_section{"under 'model'", model_keys};

void read_model_options(Reader& r, ModelSpec& model, Marks& marks) {
  for (const auto& [w, node] : r.names(marks.top, "effects")) {
    const auto& effect = effect_table[static_cast<std::size_t>(w)];
    model.effects.*effect.value = true;
    if (effect.value == &EffectSet::damping) {
      marks.damping_effect = node;
    }
  }

  const Fields f = r.section(marks.top, "model");
  SceneModelOptions options;
  r.read_bound(f, options);
  model.effects.stretch = options.stretch;
  model.surface_correction = options.surface_correction;
  model.volume_correction = options.volume_correction;
  model.mirror_coupling = options.mirror_coupling;
}

} // namespace pd::scene
