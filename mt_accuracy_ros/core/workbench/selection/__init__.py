"""Forward selection of missing effects, judged only on readings the fit did not see.

* ``linalg``        normal equations, penalised (ridge) fits, standard errors.
* ``folds``         the time-blocked cross-validation every part of the workbench uses.
* ``significance``  p-values, the max-T adjustment and the acceptance rule.
* ``designs``       the candidates' designs, sensitivities and per-fold products.
* ``selector``      the search (:class:`Selector`); its method is told there.

Everything the workbench, the commands, the benchmarks and the tests import from
``selection`` is re-exported here.
"""
from .designs import (COMPONENT_NAMES, DESIGN_CACHE_BYTES, SENSITIVITY_CACHE_BYTES,
                      _SERIALS, ReadingDesigns, Term, _BaseStatistics,
                      _largest_magnitude_per_row, _reading_caches, _ReadingCaches,
                      design_setting, penalty_of, per_target)
from .folds import _train, time_blocks
from .linalg import (NORMAL_RCOND, normal_inverse, penalise, penalised_fit, products_fit,
                     ridge_standard_errors, solve_normal, solve_normal_grouped)
from .selector import Scored, Selector, Step
from .significance import (MAX_T_DRAWS, Evidence, PassRule, block_gains, coefficient_p_value,
                           gain_p_value, max_t_adjusted)

__all__ = ["COMPONENT_NAMES", "DESIGN_CACHE_BYTES", "Evidence", "MAX_T_DRAWS", "NORMAL_RCOND",
           "PassRule",
           "SENSITIVITY_CACHE_BYTES", "ReadingDesigns", "Scored", "Selector", "Step", "Term",
           "_BaseStatistics", "_ReadingCaches", "_SERIALS", "_largest_magnitude_per_row",
           "_reading_caches", "_train", "block_gains", "coefficient_p_value",
           "design_setting", "gain_p_value", "max_t_adjusted", "normal_inverse", "penalise",
           "penalised_fit", "penalty_of", "per_target", "products_fit",
           "ridge_standard_errors", "solve_normal", "solve_normal_grouped", "time_blocks"]
