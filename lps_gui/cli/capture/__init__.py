"""`lps capture` and what it needs: devices, plan, preflight checks, segments, live results, set-up, resume."""
