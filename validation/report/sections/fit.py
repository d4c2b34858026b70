"""Section 3, the fit: the fitting method's own account of its model (``FittingMethod.describe``) and the minimal
model against its variant without cross-coupling terms."""
from __future__ import annotations

from fitting.methods.registry import get_method

from ..claims import not_significant_text
from ..context import ReportContext
from ..html import Figure, Section, Table

__all__ = ["section"]


def section(context: ReportContext) -> Section:
    """The method's paragraph, table and figures (:class:`fitting.description.MethodDescription`), then the variant
    comparison's sentence, table and figure."""
    cmp, fit_dir, model_json = context.variant, context.fit_dir, context.model_json
    rows = []
    if cmp is not None:
        rows = [["attractor shape", cmp.shape_test.median_difference, cmp.shape_test.p_greater, cmp.shape_test.n],
                ["Poincare map", cmp.poincare_test.median_difference, cmp.poincare_test.p_greater, cmp.poincare_test.n]]
    described = get_method(context.fit.method).describe(context.fit)
    fit_figs = [Figure(fit_dir / name, caption) for name, caption in described.figures if (fit_dir / name).exists()]
    if cmp is not None and (fit_dir / "compare.png").exists():
        fit_figs.append(Figure(fit_dir / "compare.png", "Per-run errors of the minimal model and of its variant without cross-coupling terms."))
    cmp_text = "" if cmp is None else (
        " Without its cross-coupling terms (re-optimised) the model's per-run errors are "
        + " and ".join(f"{'' if t.p_greater < 0.05 else 'not significantly '}larger for the {what} "
                       + not_significant_text(t.p_greater, t.n, 0.05)
                       for t, what in ((cmp.shape_test, "attractor shape"), (cmp.poincare_test, "Poincare map"))) + ".")
    fit_table = Table(described.table.title, list(described.table.header), [list(r) for r in described.table.rows])
    return Section(
        "fit", "3. The fit",
        described.text + cmp_text,
        fit_figs,
        [fit_table]
        + ([Table("Variant without cross-coupling terms vs the minimal model (per-run errors)",
                  ["error", "median difference (variant - minimal)", "Wilcoxon p (variant worse)", "runs"], rows)] if rows else []),
        {"equations": model_json["equations"], "wilcoxon_shape_p": None if cmp is None else cmp.shape_test.p_greater,
         "wilcoxon_poincare_p": None if cmp is None else cmp.poincare_test.p_greater})
