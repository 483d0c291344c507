"""The irradiance-cache calculation of Ward, Rubinstein & Clear (1988) on arrays of rays:
the ray tracer, the paths through specular surfaces, direct light, window portals and
openings, hemisphere sampling with gradients and the Hessian, the records and their
octree, placement, the level solver (``integrator``) and luminance images (``render``).
Lengths are metres, illuminance lux, luminance cd/m²."""
