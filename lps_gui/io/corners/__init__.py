"""corners.vnl in every form: the mrcal vnlog reader and fast writer, target corners, live appends, hashes."""
