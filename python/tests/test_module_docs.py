"""The module's docstrings: every public name has one, and those of the bound C++ entities are
the `///` comments of the library headers (python/docstrings.py generates them at build time),
checked here against the header lines themselves."""

import inspect
import os
import re

import pytest

import lasercell
from lasercell import _lasercell


def header_comment(source_dir, header, declaration):
    """The `///<` text on the line of `declaration` in `header`, or the `///` block above it."""
    with open(os.path.join(source_dir, header), encoding="utf-8") as f:
        lines = f.read().split("\n")
    for i, line in enumerate(lines):
        if re.search(declaration, line):
            trailing = re.search(r"///<\s?(.*)$", line)
            if trailing:
                return trailing.group(1).strip()
            block = []
            while lines[i - 1].strip().startswith("///"):
                i -= 1
                block.insert(0, lines[i].strip()[3:].strip())
            return " ".join(block)
    raise AssertionError(f"{declaration!r} not in {header}")


def doc_body(obj):
    """The docstring without pybind11's signature line(s)."""
    doc = inspect.getdoc(obj) or ""
    return "\n".join(line for line in doc.split("\n") if not re.match(r"^\w+\(.*\) ->", line))


@pytest.mark.parametrize("obj, header, declaration", [
    (lambda: lasercell.PartInstance.frame, "localize/localize_parts.hpp", r"std::string frame;"),
    (lambda: lasercell.PartInstance, "localize/localize_parts.hpp", r"^struct PartInstance \{"),
    (lambda: lasercell.localize_parts, "localize/localize_parts.hpp",
     r"^LocalizePartsResult LocalizeParts\("),
    (lambda: lasercell.ReadReport.unit_hint, "core/io/point_cloud_io.hpp", r"std::string unit_hint"),
    (lambda: lasercell.PpfModel.diameter_mm, "registration/ppf_model.hpp", r"double diameter_mm\(\)"),
    (lambda: lasercell.write_mesh, "core/io/mesh_io.hpp", r"^void WriteMesh\("),
    (lambda: lasercell.detect_peaks, "triangulation/peak_detection.hpp",
     r"^PeakDetectionResult DetectPeaks\(const ImageView8"),
    (lambda: lasercell.PeakDetectionResult.saturated, "triangulation/peak_detection.hpp",
     r"std::size_t saturated = 0;"),
    (lambda: lasercell.calibrate_handeye_sections, "calib/sphere_section_hand_eye.hpp",
     r"^SphereSectionHandEyeResult CalibrateHandEyeFromSphereSections\("),
])
def test_bound_entities_carry_their_header_comment(source_dir, obj, header, declaration):
    text = header_comment(source_dir, header, declaration)
    assert text, f"no comment for {declaration} in {header}"
    assert text in " ".join(doc_body(obj()).split()), (text, doc_body(obj()))


def public_members():
    for name in dir(_lasercell):
        if name.startswith("_") or name in ("ArrayLike", "Joints"):
            continue
        obj = getattr(_lasercell, name)
        yield name, obj
        if inspect.isclass(obj) and not issubclass(obj, BaseException):
            for member, value in vars(obj).items():
                if not member.startswith("_"):
                    yield f"{name}.{member}", value


def test_every_public_name_has_a_docstring():
    missing = [name for name, obj in public_members()
               if isinstance(obj, (property, type)) or callable(obj)
               if not doc_body(obj).strip()]
    assert missing == []
