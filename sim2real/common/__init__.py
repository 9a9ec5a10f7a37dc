"""Plumbing every script and tool shares: typed configs (``config``), one-line errors and exit codes
(``cli``), output folders that never touch what sim2real did not make (``output``), progress bars
(``progress``), headless plots (``plots``) and offscreen frames and videos (``video``)."""
from __future__ import annotations

from sim2real._lazy import exports

# public name -> "module:attribute"
_EXPORTS = {
    "ConfigError": "sim2real.common.config:ConfigError",
    "load_config": "sim2real.common.config:load",
}
__getattr__, __dir__, __all__ = exports(__name__, _EXPORTS)
