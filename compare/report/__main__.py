"""``python -m tissuemech.compare.report [--out DIR] [--quick]`` (the same as ``tissuemech report``)."""

from tissuemech.compare.cli.report import main

raise SystemExit(main())
