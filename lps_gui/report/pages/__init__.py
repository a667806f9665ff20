"""The text of every report page as plain rows: summary, verdict, budget, ISO table, planar, targets, ASME."""
