"""The terrain model below the algorithms: grids and ground spacing, the sun and its
times, ephemerides, bodies, Earth curvature and refraction."""
