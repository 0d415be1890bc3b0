// The `effects` list and the `model` section: what the bond model simulates and how its bonds are
// corrected.
#include "bind.hpp"
#include "sections.hpp"

namespace pd::scene {

namespace {

/// The model options as scene files default them: the treatment that is right in tension and in
/// bending for any box or union of boxes (issue 14). Ghost layers outside free surfaces and
/// clamps extrapolated by the quadratics that vanish on their faces give every body particle the
/// bulk energy of any quadratic field (ghost_layers.hpp); the `gradient` bond weights make that
/// bulk energy the continuum's, cell by cell, for uniform strain and for bending
/// (corrections.hpp). ModelSpec's own default stays the bare model (none + none, copy) for code
/// that assembles models directly.
struct SceneModelOptions {
  StretchKind stretch = EffectSet{}.stretch;
  SurfaceCorrection surface_correction = SurfaceCorrection::ghost;
  VolumeCorrection volume_correction = VolumeCorrection::gradient;
  MirrorCoupling mirror_coupling = MirrorCoupling::quadratic;
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
     .doc = "bond quadrature weights: partial volume of cut cells (linear, exact), "
            "moment-matched lattice weights (moment), or weights that also match a cell's "
            "bending energy (gradient: stiffness on the bonds up to 2 spacings)",
     .choices = enum_words<VolumeCorrection>,
     .bind = field_with_default<&SceneModelOptions::volume_correction>()},
    {.name = "mirror_coupling",
     .type = Type::choice,
     .doc = "mirror supports: quadratic (support particles extrapolated from the body by the "
            "quadratics that vanish on the face: symmetric, exact for every quadratic field the "
            "clamp allows), consistent (odd images, forces sent back: symmetric) or copy (odd "
            "images, one-sided, not energy-conserving)",
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
