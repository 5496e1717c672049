"""Engine adapters behind one small interface (`engines.base.Engine`), found as plugins.

    from engines import load_engine
    eng = load_engine("pinocchio", model)     # model from reference_model.load_model
    eng = load_engine("exudyn", model, build="redundant", step=1e-3)
    eng = load_engine("mypkg.engine:MyEngine", model)          # any importable Engine subclass
    eng = load_engine("path/to/my_engine.py:MyEngine", model)  # or one in a file

Engines are registered in the entry-point group ``bicycle_xval.engines`` (the built-ins in
this project's pyproject.toml, like any third party's); `engines.registry` finds them,
`engines.loading` builds them. The contract an engine fulfils is docs/engines.md.
"""

from __future__ import annotations

from .base import (CAPABILITIES, CONTACTS, CapabilityError, Engine, EngineError, EngineLoadError,
                   EngineSpecError, EngineUsageError, UnsupportedModel)
from .loading import (EngineInfo, LoadedEngines, engine_info, load_engine, load_engines,
                      parse_engine_options, split_options)
from .registry import GROUP, EngineNotInstalled, available_engines, default_engines, not_installed

# The built-in engines' names (a constant kept for existing imports; what is installed and
# registered right now, third parties' included, is `available_engines()`).
ENGINES = ("reference", "pinocchio", "exudyn")

__all__ = ["CAPABILITIES", "CONTACTS", "ENGINES", "GROUP", "CapabilityError", "Engine",
           "EngineError", "EngineInfo", "EngineLoadError", "EngineNotInstalled", "EngineSpecError",
           "EngineUsageError", "LoadedEngines", "UnsupportedModel", "available_engines", "default_engines", "engine_info",
           "load_engine", "load_engines", "not_installed", "parse_engine_options", "split_options"]
