"""Uncertainty tools: model sets, relative-error envelope, covering weight, parametric margin.

modelset     the parametric model set (perturbed denominator coefficients), responses, poles
envelope     relative errors, their envelope and its refined peak, the exact box bound, coverage
weight       the inverse-notch weight shape, and the fit of a stable minimum-phase weight
             covering an envelope
margin       exact parametric stability margin (zero exclusion) and small-gain certificates
parametric   the coefficient box as an LFT with one real block per coefficient, and the
             robust-stability margin by mixed mu
sampled      the members at a sampling rate: exact ZOH models, sampled loops with a delay,
             random draws from the box
sampled_margin  the sampled loop's parametric stability margin (vertices, edges, a sample)
polynomials  polynomial helpers shared by the modules above

Every model is passed explicitly; nothing here knows the paper.  Methods and
derivations: ``docs/uncertainty.md``.
"""

from piezolib.uncertainty.modelset import (
    MAX_MEMBERS, ModelSet, level_offsets, member_closed_loop_poles, member_poles, model_set,
    perturbed_plant, set_response, unstable_members)
from piezolib.uncertainty.envelope import (
    Coverage, SpreadBracket, coverage, envelope_peak, largest_covered_spread,
    relative_error_bound, relative_error_envelope, relative_errors)
from piezolib.uncertainty.weight import fit_covering_weight, inverse_notch_weight
from piezolib.uncertainty.margin import (
    ParametricMargin, parametric_stability_margin, small_gain_spread, stability_gauge,
    weight_certified_spread)
from piezolib.uncertainty.sampled import (
    member_zoh_coefficients, random_model_set, sampled_loop_poles, sampled_loop_spread,
    sampled_loop_unstable)
from piezolib.uncertainty.sampled_margin import SampledMargin, sampled_parametric_margin

__all__ = [
    "ModelSet", "model_set", "level_offsets", "perturbed_plant", "set_response",
    "relative_errors",
    "member_poles", "member_closed_loop_poles", "unstable_members", "relative_error_envelope",
    "envelope_peak", "relative_error_bound", "Coverage", "coverage",
    "SpreadBracket", "largest_covered_spread", "inverse_notch_weight", "fit_covering_weight",
    "ParametricMargin", "stability_gauge", "parametric_stability_margin",
    "small_gain_spread", "weight_certified_spread", "MAX_MEMBERS",
    "random_model_set", "member_zoh_coefficients", "sampled_loop_poles", "sampled_loop_unstable",
    "sampled_loop_spread", "SampledMargin", "sampled_parametric_margin",
]
