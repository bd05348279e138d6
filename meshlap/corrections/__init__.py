"""Stage 5 of the pipeline: what turns the kernel operator into the accurate one.

* :mod:`~meshlap.corrections.images`: mirror images across the boundary (Neumann spectra),
  for curves, surfaces, volumes and clouds alike;
* :mod:`~meshlap.corrections.moments`: the global second-moment scale (symmetric) and the
  point-wise rows exact for quadratics (what ``op @ f`` applies);
* :mod:`~meshlap.corrections.psd`: the semidefiniteness check of the Richardson kernel, with
  the plain kernel as its fallback.

The Richardson (difference of Gaussians) kernel itself is a kernel choice, made in
:mod:`meshlap.assembly`.
"""

from . import images, moments, psd
from .images import neumann_images
from .moments import moment_correction, second_moment_scale

__all__ = ["images", "moment_correction", "moments", "neumann_images", "psd", "second_moment_scale"]
