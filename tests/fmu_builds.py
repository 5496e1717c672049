"""The FMUs the FMU tests read, built once per version of their sources into the code cache
(gcc on the generated C, ~3-5 s cold each; written atomically, so two pytest-xdist workers
building one at once both end with an intact file)."""

import atexit
import hashlib
import os
import shutil
import tempfile
from pathlib import Path

from reference_model.equations import codegen
from reference_model.exports import fmu as fmu_export

__all__ = ["cached_fmu"]


def cached_fmu(model, co_simulation: bool = False, directional_derivatives: bool = True) -> Path:
    """The FMU of ``model`` (``write_fmu``'s options), from the cache or built now.

    Under mutmut (its protocol: ``MUTANT_UNDER_TEST`` names the mutant being run) the export
    module's file holds every mutant at once, so its bytes key one FMU for all of them: the
    first build was served to every mutant after it, and 778 of the export's 851 first mutants
    survived. For a mutant of the export each call builds afresh, into a temporary folder, and
    nothing is cached; any other mutant (an FMU engine's) cannot change the build and is served
    from the cache."""
    if os.environ.get("MUTANT_UNDER_TEST", "").startswith(fmu_export.__name__ + "."):
        folder = tempfile.mkdtemp(prefix="bicycle-xval-fmu-mutant-")
        atexit.register(shutil.rmtree, folder, True)
        out = Path(folder) / f"{model.name}.fmu"
        return fmu_export.write_fmu(model, out, co_simulation=co_simulation,
                                    directional_derivatives=directional_derivatives)
    h = hashlib.sha256(b"cs" if co_simulation else b"me")
    h.update(b"dd" if directional_derivatives else b"fd")
    for path in (fmu_export.WRAPPER, Path(fmu_export.__file__)):
        h.update(path.read_bytes())
    h.update(model.library.key.encode() + model.params.vector().tobytes())
    out = codegen.cache_root() / "fmu-tests" / f"{model.name}-{h.hexdigest()[:16]}.fmu"
    if not out.is_file():
        out.parent.mkdir(parents=True, exist_ok=True)
        fmu_export.write_fmu(model, out, co_simulation=co_simulation,
                             directional_derivatives=directional_derivatives)
    return out
