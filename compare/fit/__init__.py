r"""Fit the lumped generalized-Maxwell spheroid model to compression-relaxation records.

Where things are: :mod:`.records` (Record, the CSV reader, the checks a record must pass), :mod:`.model`
(parameters, the JAX residual and its Jacobian, bounds, the model-error term of a law), :mod:`.problem`
(weighted residuals, the bounded solver), :mod:`.intervals` (Wald / profile intervals, identifiability),
:mod:`.diagnostics` (residual diagnostics, the error model of the intervals), :mod:`.result` (FitResult),
:mod:`.estimation` (:func:`relaxation`), :mod:`.protocols` (:func:`records_fit`: creep, measured-history and mixed
records), :mod:`.design` (experiment design: predicted interval widths),
:mod:`.fe` (:func:`fe_relaxation`, :func:`fe_indentation`: the FE in the loop, exact FE Jacobians, beyond the
reduced model's tables).
The names below are re-exported here: ``from tissuemech.compare.fit import relaxation, read_csv, FitResult,
Record``.

Model (``reduced.spheroid``; SI units): for a ball of radius ``a0`` (m) pressed by a total approach
``delta(t)`` (m, linear ramp over ``ramp_time`` then held), the nominal stress is

    sigma~(t) = F(t) / A_mid(t),   F(t) = F_eq(delta(t); C, alpha) + sum_m q_m(t),
    dq_m/dt = -q_m / tau_m + beta_m dF_eq(delta(t))/dt,

with the Fung stiffness ``C`` (Pa), exponent ``alpha`` (-), energy factors ``beta_m`` (-) and
relaxation times ``tau_m`` (s).

Statistical model
-----------------
Record j (one compression level) is  y_jk = m_jk(theta) (1 + e_j) + s_j eps_jk  with white Gaussian
noise eps of unknown standard deviation ``s_j`` (Pa, estimated per record, so records of different
stress levels are weighted by their own noise) and an optional **model-error** factor
e_j ~ N(0, model_error^2): a relative error of the equilibrium law common to the whole record (a
mis-tabulated F_eq at that compression scales the elastic and the viscous force alike). The e_j are
nuisance parameters with a Gaussian prior, estimated jointly and marginalised in the covariance. By
default (``model_error="auto"``) the FE master table's own error estimate is used (metadata key
``model_error_rel``, relative 1-sigma error of the equilibrium force; :data:`DEFAULT_MODEL_ERROR_REL`
when the table lacks it); for ``"hertz"``, a user table or a callable the law is taken as exact (0).

Estimation: weighted least squares in log-parameters ``theta = log p`` (all positive; ``alpha`` kept
in ``[1e-6, alpha_max]``, alpha_max = the table's upper alpha for table laws, else 10), by
``scipy.optimize.least_squares`` (trust region) with the exact Jacobian ``jax.jacfwd`` through the
JAX model: an unweighted pass, the per-record noise estimate s_j^2 = RSS_j / (n_j - P n_j / N), a
weighted pass.

Intervals (95 %): by default (``errors="robust"``, :mod:`.diagnostics`) ``sd_i`` comes from a covariance that
allows for a smooth model misfit of estimated size and for correlated, uneven noise (never below the
Gauss-Newton one), and the profile threshold ``t^2`` below is raised by the same variance ratio;
``errors="white"`` keeps the Gauss-Newton covariance. The Wald interval ``theta_i +- t sd_i`` is checked against the
profile likelihood: at each Wald end the other parameters are re-optimised, and if the rise of the
chi-square there is not within 10 % of ``t^2`` (t the 97.5 % Student quantile with N - P degrees of
freedom) the end is replaced by the root of the profile (``chi2_profile(theta_i) - chi2_min = t^2``,
Brent). A profile that stays below ``t^2`` up to a search bound gives a one-sided interval (e.g.
alpha in [0, 0.9]: "alpha < 0.9 at 95 %"), one that stays below it without bound an open end (inf).
Records without information raise ValueError (fewer points than parameters, constant or
non-positive stress); round-off-level residuals (noise-free data) and a model that does not depend
on a parameter are flagged, with NaN or full-range intervals instead of zero widths. Records that scatter
about the model by less than the equilibrium table's own stated accuracy (metadata ``model_error_rel``; noise
sd below that fraction of the record's peak) are flagged too (``success`` False): their residuals are then the
records' own discretisation error and the model's rather than noise (noise-free FE-made records: the fit
moves alpha to absorb the mesh's error and the intervals shrink below that bias).

Identifiability: the eigen-decomposition of the (model-error-marginalised) Fisher matrix in log
space: an eigenvector ``v`` with eigenvalue ``lam`` says the combination ``prod_i p_i^{v_i}`` is known
to a relative standard deviation of about ``1/sqrt(lam)``. With ONE compression level only
``F_eq(delta)`` is seen, so ``C`` and ``alpha`` trade off along one direction (tiny eigenvalue,
eigenvector mixing C and alpha); two or more levels separate them (provided the equilibrium law
depends on alpha; the small-strain Hertz law does not).
"""

from __future__ import annotations

from tissuemech.compare.fit.estimation import NOISE_FREE_REL, relaxation
from tissuemech.compare.fit.fe import FEFitResult, fe_indentation, fe_relaxation, step_times
from tissuemech.compare.fit.intervals import LOG_SPAN, POOR_SD, WALD_TOL, Z95, Identifiability
from tissuemech.compare.fit.model import (
    ALPHA_BOUNDS,
    BETA_BOUNDS,
    DEFAULT_MODEL_ERROR_REL,
    PARAMETER_UNITS,
    TAU_SPAN,
    default_model,
    incompressible_model,
    initial_guess,
    model_error_of,
    parameter_names,
    table_of,
)
from tissuemech.compare.fit.protocols import CreepRecord, HistoryRecord, records_fit
from tissuemech.compare.fit.records import (
    COLUMN_UNITS,
    Record,
    Table,
    check_record,
    load_records,
    read_csv,
    read_table,
)
from tissuemech.compare.fit.result import FitResult

__all__ = [
    "fe_relaxation",
    "fe_indentation",
    "FEFitResult",
    "step_times",
    "Record",
    "CreepRecord",
    "HistoryRecord",
    "records_fit",
    "FitResult",
    "Identifiability",
    "relaxation",
    "read_csv",
    "read_table",
    "load_records",
    "Table",
    "parameter_names",
    "check_record",
    "model_error_of",
    "table_of",
    "initial_guess",
    "default_model",
    "incompressible_model",
    "Z95",
    "DEFAULT_MODEL_ERROR_REL",
    "ALPHA_BOUNDS",
    "BETA_BOUNDS",
    "TAU_SPAN",
    "POOR_SD",
    "NOISE_FREE_REL",
    "WALD_TOL",
    "LOG_SPAN",
    "PARAMETER_UNITS",
    "COLUMN_UNITS",
]
