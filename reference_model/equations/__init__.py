"""The equations of motion and their code, by job (each module imports only those above it):

* ``derivation``: the symbolic derivation (sympy), the thesis's Newton-Euler equations;
* ``emit``: printing them as C or numpy (common subexpressions, straight-line functions);
* ``runtime.c`` and ``numpy_runtime``: the KKT solves the generated code calls, in C
  (#included) and in numpy;
* ``codegen``: generating, compiling, caching (keyed by the sources above) and loading it.

Nothing is imported here: sympy is imported only when code is generated, so a process that
loads cached code never pays for it (``reference_model.equations.codegen``'s docstring). The
older modules ``reference_model.derivation``, ``codegen``, ``codegen_emit`` and
``numpy_runtime`` re-export from here.
"""

__all__: list[str] = []
