"""The stages of `bicycle-xval run`, listed once, in report order (`stage.Stage`: each says
what tasks it needs and how it assembles their results). The scenario runs and their
comparison, which every other part leans on, are the pipeline's own core."""

from __future__ import annotations

from .benchmark import BenchmarkStage
from .energy import EnergyStage
from .engine_eigenvalues import EngineEigenvaluesStage
from .faults import FaultsStage
from .fixed_step import FixedStepStage
from .linear_check import LinearCheckStage
from .option_study import OptionStudyStage
from .soft_contact import SoftContactStage
from .stability import StabilityStage
from .terms import TermsStage

__all__ = ["SECTIONS", "STAGES"]

STAGES = (StabilityStage(), TermsStage(), FixedStepStage(), EnergyStage(), SoftContactStage(),
          BenchmarkStage(), LinearCheckStage(), EngineEigenvaluesStage(), OptionStudyStage(),
          FaultsStage())
#: the parts of a run besides the scenarios, selectable with --sections (all by default)
SECTIONS = tuple(dict.fromkeys(s.section for s in STAGES if s.section is not None))
