"""tissuemech.compare: where the reduced and FE halves meet (scans, benchmarks, figures, CLI)."""
