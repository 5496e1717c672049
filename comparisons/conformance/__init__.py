"""The engine conformance suite: every check the harness makes of an engine, as a pytest plugin
any implementation can run.

    pip install bicycle-xval                      # registers the plugin (entry point pytest11)
    pytest --pyargs comparisons.conformance --engine mypkg.engine:MyEngine \\
           [--engine-option key=value ...] [--model thesis-disc --model my_bike.toml] \\
           [--xfails-file xfails.txt]

Against the reference model built from the same parameters, for every engine and model (and
only what the engine's capabilities allow; a model the engine does not support is listed in
the header, not failed): each term (M, inverse dynamics, gravity, generalized forces, D,
dD dq, constrained ddq) at hypothesis states and at a deterministic sweep of 200 states; the
zig-zag's torques and multipliers through the engine's inverse dynamics; forward trajectories
up to the meaningful horizon. Failures name the term, the entry and the state.

Expected failures: ``--xfails-file F``, one check id per line followed by ``#`` and the reason
(array-api-tests' convention), e.g.
``test_term_sweep[myengine-thesis-constraint_bias]  # dD dq not implemented for the thesis contact``;
a listed check that passes is reported as a failure (strict), so the list stays true.

Without ``--engine``, the built-in engines other than the reference are checked (this is how
the project's own test suite runs Pinocchio and Exudyn). Models default to ``thesis``,
``thesis-disc``, ``benchmark`` and the two conformance bicycles ``general`` and
``general-disc`` (`models.py`: every inertia entry distinct, unequal wheels, an off-axis fork
centre of mass, so a swapped key or frame cannot hide); without ``--model`` the forward runs
(seconds each) are checked on ``thesis-disc`` and ``general`` only.
"""
