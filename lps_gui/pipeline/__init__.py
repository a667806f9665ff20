"""Jobs over sessions: detect, estimate, the results document's sections, compensation, export, live results, demos."""
