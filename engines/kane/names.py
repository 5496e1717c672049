"""The names of the Kane derivation's inputs, in the order the generated code takes them (no
sympy here: the engine needs them without the derivation)."""

#: Moore's parameters in the order the generated code takes them (p[i]).
MOORE_PARAMETERS: tuple[str, ...] = (
    "rr", "rf", "d1", "d2", "d3", "l1", "l2", "l3", "l4",
    "mc", "md", "me", "mf",
    "IDxx", "IDyy", "IDzz", "ICxx", "ICyy", "ICzz", "ICxz",
    "IExx", "IEyy", "IEzz", "IExz", "IFxx", "IFyy", "IFzz",
    "g", "cv",
)
#: The rider torques [steer, pedal, anti-roll] (the thesis's [Mdir, Mped, Mvue]).
TORQUES: tuple[str, ...] = ("T_dir", "T_ped", "T_vue")
