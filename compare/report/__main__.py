"""``python -m tissuemech.compare.report [--out DIR] [--quick]``."""

from tissuemech.compare.report.build import main

raise SystemExit(main())
