"""Moved: `rostool bag plot` is rostool/commands/bag/plot.py; OUTPUT_HELP lives in rostool/output/plot_file.py
(kept here for the modules that still import it from this place)."""

from rostool.output.plot_file import OUTPUT_HELP

__all__ = ["OUTPUT_HELP"]
