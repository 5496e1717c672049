"""The model's names, without sympy: coordinates, bodies, rider torques and points.

`derivation` derives the equations in these names; every module that only needs the names
(the numeric model, export, linearization, Moore's map) imports them from here, so loading a
model does not import sympy.
"""

COORDINATES = ("xc", "yc", "phi", "theta", "psi", "beta", "gamma", "eps")
BODIES = (2, 3, 4, 5)
BODY_NAMES = {2: "rear wheel", 3: "frame+rider", 4: "fork/handlebar", 5: "front wheel"}
TORQUE_NAMES = ("Mdir", "Mped", "Mvue")
#: the points whose positions the generated code evaluates (in this order)
POINT_NAMES = ("rC", "rA", "rG2", "rG3", "rG4", "rG5", "rD")
