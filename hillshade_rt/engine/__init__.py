"""The engine above the algorithms: a DEM prepared once and lit by many suns (the
shader), the GPU runtime, per-cell suns on a body, products, the irradiance
physics, the array API and the window job of runs larger than memory."""
