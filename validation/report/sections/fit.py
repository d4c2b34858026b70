"""Section 3, the fit: the fitting method's own account of its model (``FittingMethod.describe``) and the minimal
model against its variant without cross-coupling terms."""
from __future__ import annotations

from ..claims import not_significant_text
from ..context import ReportContext
from ..html import Figure, Section, Table

__all__ = ["section"]


def section(context: ReportContext) -> Section:
    """The method's paragraph, table and figures (:class:`fitting.description.MethodDescription`), then the variant
    comparison's sentence, table and figure."""
    cmp, fit_dir, model_json = context.variant, context.fit_dir, context.model_json
    rows = []
    tests = [] if cmp is None else [(cmp["wilcoxon_shape"], "attractor shape"), (cmp["wilcoxon_poincare"], "Poincare map")]
    for t, what in tests:
        rows.append([what, t["median_difference"], t["p_greater"], t["n"]])
    described = context.described
    fit_figs = [Figure(fit_dir / name, caption) for name, caption in described.figures if (fit_dir / name).exists()]
    if cmp is not None and (fit_dir / "compare.png").exists():
        fit_figs.append(Figure(fit_dir / "compare.png", "Per-run errors of the minimal model and of its variant without cross-coupling terms."))
    cmp_text = "" if cmp is None else (
        " Without its cross-coupling terms (re-optimised) the model's per-run errors are "
        + " and ".join(f"{'' if t['p_greater'] < 0.05 else 'not significantly '}larger for the {what} "
                       + not_significant_text(t["p_greater"], t["n"], 0.05) for t, what in tests) + ".")
    fit_table = Table(described.table.title, list(described.table.header), [list(r) for r in described.table.rows])
    return Section(
        "fit", "3. The fit",
        described.text + cmp_text,
        fit_figs,
        [fit_table]
        + ([Table("Variant without cross-coupling terms vs the minimal model (per-run errors)",
                  ["error", "median difference (variant - minimal)", "Wilcoxon p (variant worse)", "runs"], rows)] if rows else []),
        {"equations": model_json["equations"], "wilcoxon_shape_p": None if cmp is None else cmp["wilcoxon_shape"]["p_greater"],
         "wilcoxon_poincare_p": None if cmp is None else cmp["wilcoxon_poincare"]["p_greater"]})
