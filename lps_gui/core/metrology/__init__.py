"""Figures of merit and their uncertainty: ISO 230-2, ASME B5.64, error motions, resolution, GUM budget, compensation."""
