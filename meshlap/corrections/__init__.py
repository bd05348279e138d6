"""Stage 5 of the pipeline: what turns the kernel operator into the accurate one.

* :mod:`~meshlap.corrections.images`: mirror images across the boundary (Neumann spectra),
  for curves, surfaces, volumes and clouds alike;
* :mod:`~meshlap.corrections.moments`: the global second-moment scale (symmetric) and the
  point-wise rows exact for quadratics (what ``op @ f`` applies);
* :mod:`~meshlap.corrections.galerkin`: the symmetric pencil from the kernel integrated over
  the cells with the hat functions, for coarse meshes and curves (``quadrature="galerkin"``),
  without the pairs :mod:`~meshlap.corrections.shortcuts` finds through the air, its width
  narrower next to creases and on thin parts (:mod:`~meshlap.corrections.features`);
* :mod:`~meshlap.corrections.psd`: the semidefiniteness check of the Richardson kernel, with
  the plain kernel as its fallback;
* :mod:`~meshlap.corrections.highorder` and :mod:`~meshlap.corrections.rowchoice`: point-wise
  rows exact for polynomials up to degree 6 in local coordinates of the fitted manifold, and
  their width and degree chosen per point from the data (``pointwise="fit"``), fitted on
  distinct points and given to coincident copies (:mod:`~meshlap.corrections.copies`).

The Richardson (difference of Gaussians) kernel itself is a kernel choice, made in
:mod:`meshlap.assembly`.
"""

from . import copies, features, galerkin, highorder, images, moments, psd, rowchoice, shortcuts
from .images import neumann_images
from .moments import moment_correction, second_moment_scale

__all__ = ["copies", "features", "galerkin", "highorder", "images", "moment_correction", "moments",
           "neumann_images", "psd", "rowchoice", "second_moment_scale", "shortcuts"]
