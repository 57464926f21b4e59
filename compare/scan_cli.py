"""Former home of ``tissuemech scan``: an alias of ``compare.cli.scan``."""

from tissuemech.compare.cli.scan import (
    BLASTULA_OPTIONS,
    SPHEROID_OPTIONS,
    ScanInputError,
    add_parser,
    parse_value,
    run,
)

__all__ = ["add_parser", "run", "parse_value", "ScanInputError", "SPHEROID_OPTIONS", "BLASTULA_OPTIONS"]
