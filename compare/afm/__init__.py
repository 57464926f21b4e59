"""Real AFM records: instrument readers, contact point, indentation history, the relaxation fit.

:mod:`.records`  :class:`~.records.Curve`, JPK (via ``afmformats``, the ``afm`` extra) and CSV readers
:mod:`.contact`  contact point on the approach (baseline + power law), indentation history, hold segment
:mod:`.fit`      the lumped Maxwell probe model (``reduced.indentation``) fitted to the hold, one curve at a time
:mod:`.study`    every curve of a study: contact, history, 1- and 2-branch fits, the printed table

The walk-through with the measured numbers: docs/afm.md; the figure: :mod:`tissuemech.compare.plots.afm`.
"""
