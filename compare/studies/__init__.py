"""The studies, each a set of functions returning tidy pandas tables (units in the column names).

* :mod:`~tissuemech.compare.studies.checks`: how far the reduced models can be trusted, case by case
  (reduced vs FE; ``tissuemech checks``);
* :mod:`~tissuemech.compare.studies.accuracy`: every method's error against its wall time (error vs
  an exact or finest-mesh reference);
* :mod:`~tissuemech.compare.studies.stability`: each method pushed until it fails;
* :mod:`~tissuemech.compare.studies.coverage`: coverage of the fit's 95 % intervals;
* :mod:`~tissuemech.compare.studies.tensiometry`: the classic tensiometry formula against the exact drop and FE.

They use :mod:`tissuemech.compare.cases` and :mod:`tissuemech.compare.reference`, never the benchmarks.
"""
