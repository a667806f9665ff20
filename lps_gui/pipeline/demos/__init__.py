"""`lps demo` in all its forms: the simulated rig end to end, its shared steps and its printed summary."""
