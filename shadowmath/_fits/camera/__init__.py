"""Engine-neutral shadow cameras of every fit: :func:`shadow_camera` (:mod:`._shadow_camera`)."""
