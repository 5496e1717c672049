"""Engine adapters behind one small interface (`engines.base.Engine`), found as plugins.

    from engines import available_engines, load_engine
    available_engines()                        # the registered names ('bicycle-xval engines')
    eng = load_engine(name, model)             # model from reference_model.load_model
    eng = load_engine(name, model, step=1e-3)  # with options its __init__ takes
    eng = load_engine("mypkg.engine:MyEngine", model)          # any importable Engine subclass
    eng = load_engine("path/to/my_engine.py:MyEngine", model)  # or one in a file

Engines are registered in the entry-point group ``bicycle_xval.engines`` (the built-ins in
this project's pyproject.toml, like any third party's); `engines.registry` finds them,
`engines.loading` builds them, `engines.facts` reads what each declares about itself and
`engines.defaults` which ones a command uses when the user names none. The contract an engine
fulfils is docs/engines.md.
"""

from __future__ import annotations

from .base import (CAPABILITIES, CONTACTS, CapabilityError, Engine, EngineError, EngineLoadError,
                   EngineSpecError, EngineUsageError, UnsupportedModel)
from .defaults import installed_engines, term_engines
from .loading import (EngineInfo, LoadedEngines, engine_info, load_engine, load_engines,
                      parse_engine_options, split_options)
from .registry import GROUP, EngineNotInstalled, available_engines, default_engines, not_installed

__all__ = ["CAPABILITIES", "CONTACTS", "GROUP", "CapabilityError", "Engine",
           "EngineError", "EngineInfo", "EngineLoadError", "EngineNotInstalled", "EngineSpecError",
           "EngineUsageError", "LoadedEngines", "UnsupportedModel", "available_engines",
           "default_engines", "engine_info", "installed_engines", "load_engine", "load_engines",
           "not_installed", "parse_engine_options", "split_options", "term_engines"]
