"""python/docstrings.py, the generator of the bindings' docstrings from the headers' `///`
comments: each rule on a small header with exact keys and texts, then on a real header."""

import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
import textwrap

import pytest


@pytest.fixture(scope="module")
def source_root():
    """$LASERCELL_SOURCE_DIR as ctest sets it; else the checkout holding this file (the generator
    needs no build, so these tests also run straight from the source tree)."""
    here = os.path.dirname(os.path.abspath(__file__))
    return os.environ.get("LASERCELL_SOURCE_DIR") or os.path.dirname(os.path.dirname(here))


@pytest.fixture(scope="module")
def docstrings(source_root):
    path = os.path.join(source_root, "python/docstrings.py")
    spec = importlib.util.spec_from_file_location("lasercell_docstrings", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture
def generate(docstrings, tmp_path, capsys):
    """Writes the given headers (core_hpp=text: core.hpp) and runs the generator on them with
    paths relative to --root; returns the keys and texts of the JSON file beside the header."""

    def run(**headers):
        names = [name.replace("_hpp", ".hpp") for name in headers]
        for name, text in zip(names, headers.values()):
            (tmp_path / name).write_text(textwrap.dedent(text))
        out = tmp_path / "generated/docstrings.hpp"
        assert docstrings.main(["--root", str(tmp_path), "--out", str(out), *names]) == 0
        assert capsys.readouterr().err == ""  # every documented declaration had a name
        return json.loads((tmp_path / "generated/docstrings.hpp.json").read_text())

    return run


def test_a_leading_block_documents_the_next_declaration(generate):
    docs = generate(core_hpp="""\
        #pragma once
        // A plain comment, not documentation.
        namespace lasercell {

        /// A box: `side` in mm,
        /// with "quotes" and a \\ backslash.
        ///
        /// A second paragraph
        ///     joined into one line.
        struct Box {
          double side = 1.0;
          // A plain comment.
          /// Kept inside the box.
          bool empty = false;
        };

        /// A template function.
        template <typename T,
                  typename U = std::vector<T>>
        [[nodiscard]] T Largest(const U& values,
                                int count = 1);
        }  // namespace lasercell
        """)
    assert docs == {
        "core_Box": 'A box: `side` in mm, with "quotes" and a \\ backslash.\n\n'
                    "A second paragraph joined into one line.",
        "core_Box_empty": "Kept inside the box.",
        "core_Largest": "A template function.",
    }


def test_a_trailing_comment_documents_its_member(generate):
    docs = generate(core_hpp="""\
        namespace lasercell {
        struct Options {
          double a = 1.0;                                ///< Side a.
          Eigen::Vector3d n = Eigen::Vector3d::UnitZ();  ///< Not a function: ( after =.
          std::optional<Matrix6d> c;                     ///< Unset when unknown.
          CircleFitOptions circle{.inlier_gate_mm = 0.2};  ///< Brace-initialized.
          std::function<void(double)> progress;          ///< ( inside <>.
          int width = 0, height = 0;                     ///< Image size.
          registration::LocalizeOptions localize;  ///< Base options (max_instances,
                                                   ///< viewpoint).
          double undocumented = 0.0;
          std::size_t dropped =
              0;  ///< Spans two lines.
        };
        }  // namespace lasercell
        """)
    assert docs == {
        "core_Options_a": "Side a.",
        "core_Options_n": "Not a function: ( after =.",
        "core_Options_c": "Unset when unknown.",
        "core_Options_circle": "Brace-initialized.",
        "core_Options_progress": "( inside <>.",
        "core_Options_width": "Image size.",
        "core_Options_height": "Image size.",
        "core_Options_localize": "Base options (max_instances, viewpoint).",
        "core_Options_dropped": "Spans two lines.",
    }


def test_nested_classes_methods_and_what_is_skipped(generate):
    docs = generate(core_hpp="""\
        namespace lasercell {
        /// Outer.
        class Outer {
         public:
          /// Builds it.
          explicit Outer(int n);
          /// Not documented: a destructor.
          ~Outer();
          /// Not documented: an operator.
          bool operator==(const Outer& other) const;
          /// With a body.
          [[nodiscard]] int Size() const { return n_; }
          /// Nested.
          struct Inner {
            int k = 0;  ///< Inner k.
          };
          /// Back in Outer.
          void Check(const Options& options = {}, Callback done = [] { return; }) const;
          /* A block comment { */
          /*
           * over lines {
           */

         private:
          int n_ = 0;  ///< Private, still a member.
          /// At the end of Outer: documents nothing.
        };
        /// A template.
        template <typename Pixel,
                  typename = std::enable_if_t<std::is_integral_v<Pixel>>>
        struct ImageView {
          int stride = 0;  ///< Pixels per row.
        };
        /// With an attribute.
        struct [[nodiscard]] Summary {
          int lines = 0;  ///< Line count.
        };
        /// After Outer.
        inline constexpr int kAnswer = 42;
        /// An alias.
        using Outers = std::vector<Outer>;
        }  // namespace lasercell
        """)
    assert docs == {
        "core_Outer": "Outer.",
        "core_Outer_Outer": "Builds it.",
        "core_Outer_Size": "With a body.",
        "core_Outer_Inner": "Nested.",
        "core_Outer_Inner_k": "Inner k.",
        "core_Outer_Check": "Back in Outer.",
        "core_Outer_n_": "Private, still a member.",
        "core_ImageView": "A template.",
        "core_ImageView_stride": "Pixels per row.",
        "core_Summary": "With an attribute.",
        "core_Summary_lines": "Line count.",
        "core_kAnswer": "After Outer.",
        "core_Outers": "An alias.",
    }


def test_enumerators_are_keyed_under_their_enum(generate):
    docs = generate(core_hpp="""\
        namespace lasercell::triangulation {
        /// Estimator.
        enum class PeakEstimator : std::uint8_t {
          kGaussian,  ///< Gaussian fit.
          /// Leading comment of an enumerator.
          kCentre = 2,
          kUndocumented,
          kLast  ///< Last, without a comma.
        };
        /// Plain enum.
        enum Plain { kA, kB };
        /// After the enums.
        int After();
        }  // namespace lasercell::triangulation
        """)
    assert docs == {
        "triangulation_PeakEstimator": "Estimator.",
        "triangulation_PeakEstimator_kGaussian": "Gaussian fit.",
        "triangulation_PeakEstimator_kCentre": "Leading comment of an enumerator.",
        "triangulation_PeakEstimator_kLast": "Last, without a comma.",
        "triangulation_Plain": "Plain enum.",
        "triangulation_After": "After the enums.",
    }


def test_overloads_keep_one_text_or_join_different_ones(generate):
    docs = generate(a_hpp="""\
        namespace lasercell::triangulation {
        /// Peaks of an 8-bit image.
        Result DetectPeaks(const ImageView8& image, const Options& options);
        /// Peaks of a 16-bit image.
        Result DetectPeaks(const ImageView16& image, const Options& options);
        /// The same text.
        int Twice(int a);
        /// The same text.
        int Twice(double a);
        }  // namespace lasercell::triangulation
        """, b_hpp="""\
        namespace lasercell::triangulation {
        /// From another header.
        Result DetectPeaks(const ImageView32& image);
        }  // namespace lasercell::triangulation
        """)
    assert docs == {
        "triangulation_DetectPeaks": "Peaks of an 8-bit image.\n\nPeaks of a 16-bit image.\n\n"
                                     "From another header.",
        "triangulation_Twice": "The same text.",
    }


def test_namespaces_give_the_prefix(generate):
    docs = generate(namespaces_hpp="""\
        #pragma once
        namespace lasercell {
        /// Root namespace.
        int Root();
        namespace io {
        /// Nested namespace io.
        Mesh ReadMesh(const std::string& path);
        }  // namespace io
        namespace {
        /// Anonymous: skipped.
        int Hidden();
        }  // namespace
        namespace detail {
        /// Detail: skipped.
        struct Helper {};
        }  // namespace detail
        }  // namespace lasercell
        namespace lasercell::calib {
        /// Options.
        struct SphereSectionHandEyeOptions {
          double sphere_radius_mm = 12.7;  ///< Sphere radius, mm.
        };
        }  // namespace lasercell::calib
        namespace lasercell::io::detail {
        /// Skipped.
        int Codec();
        }  // namespace lasercell::io::detail
        namespace other {
        /// Outside lasercell: skipped.
        int Foreign();
        }  // namespace other
        namespace lasercell {
        /// Back at the root.
        int Again();
        }  // namespace lasercell
        """)
    assert docs == {
        "core_Root": "Root namespace.",
        "io_ReadMesh": "Nested namespace io.",
        "calib_SphereSectionHandEyeOptions": "Options.",
        "calib_SphereSectionHandEyeOptions_sphere_radius_mm": "Sphere radius, mm.",
        "core_Again": "Back at the root.",
    }


def test_bodies_macros_and_literals_keep_the_braces_counted(generate):
    docs = generate(core_hpp="""\
        namespace lasercell {
        /// Documents a macro, not the next declaration.
        #define LASERCELL_BEGIN(x) \\
          {                        \\
            int x = 0;
        int Undocumented();
        /// A body; declarations inside are not documented.
        inline int Body() {
          /// Not a key.
          int local = 1;
          if (local) { local = 2; }
          return local;
        }
        /// Literals do not count.
        struct Literals {
          std::string open = "{ // not a comment";  ///< Brace in a string.
          char close = '}';                         ///< Brace in a char.
          int big = 1'000;                          ///< Digit separator.
        };
        /// After them.
        int After();
        }  // namespace lasercell
        """)
    assert docs == {
        "core_Body": "A body; declarations inside are not documented.",
        "core_Literals": "Literals do not count.",
        "core_Literals_open": "Brace in a string.",
        "core_Literals_close": "Brace in a char.",
        "core_Literals_big": "Digit separator.",
        "core_After": "After them.",
    }


def test_the_generated_header(docstrings, generate, tmp_path):
    generate(core_hpp="""\
        namespace lasercell {
        /// Zeta "quoted" \\n,
        /// two lines.
        ///
        /// Second paragraph.
        int Zeta();
        /// Alpha.
        int Alpha();
        }  // namespace lasercell
        """)
    out = tmp_path / "generated/docstrings.hpp"
    lines = out.read_text().splitlines()
    assert lines[0] == "#pragma once"
    assert "generated by python/docstrings.py" in out.read_text().lower()
    assert "#define LC_DOC(key) LASERCELL_DOC_##key" in lines
    defines = [line for line in lines if line.startswith("#define LASERCELL_DOC_")]
    assert defines == [
        '#define LASERCELL_DOC_core_Alpha R"lcdoc(Alpha.)lcdoc"',
        '#define LASERCELL_DOC_core_Zeta R"lcdoc(Zeta "quoted" \\n, two lines.)lcdoc" "\\n\\n" '
        'R"lcdoc(Second paragraph.)lcdoc"',
    ]
    # Unchanged content: neither file is rewritten (the build then recompiles nothing).
    stats = [os.stat(path) for path in (out, str(out) + ".json")]
    header = str(tmp_path / "core.hpp")  # absolute, without --root
    assert docstrings.main(["--out", str(out), header]) == 0
    assert [os.stat(path) for path in (out, str(out) + ".json")] == stats
    assert sorted(os.listdir(tmp_path / "generated")) == ["docstrings.hpp", "docstrings.hpp.json"]


def test_errors(docstrings, tmp_path):
    def run(*headers):
        return subprocess.run([sys.executable, docstrings.__file__, "--root", str(tmp_path),
                               "--out", str(tmp_path / "docstrings.hpp"), *headers],
                              capture_output=True, text=True, check=False)

    (tmp_path / "good.hpp").write_text("namespace lasercell {\n/// Fine.\nint G();\n}\n")
    done = run("good.hpp", "missing.hpp")
    assert done.returncode == 2
    assert len(done.stderr.splitlines()) == 1 and "missing.hpp" in done.stderr
    (tmp_path / "bad.hpp").write_text('namespace lasercell {\n/// )lcdoc" ends it.\nint F();\n}\n')
    done = run("good.hpp", "bad.hpp")
    assert done.returncode == 1 and "core_F" in done.stderr and ')lcdoc"' in done.stderr
    assert not (tmp_path / "docstrings.hpp").exists()


def test_the_header_compiles_to_the_texts(generate, tmp_path):
    compiler = shutil.which("c++") or shutil.which("g++")
    if not compiler:
        pytest.skip("no C++ compiler")
    docs = generate(core_hpp="""\
        namespace lasercell {
        /// Quotes "q", a backslash \\ and `ticks`.
        ///
        /// Second paragraph.
        int Zeta();
        }  // namespace lasercell
        """)
    (tmp_path / "main.cpp").write_text(
        '#include <cstdio>\n#include "docstrings.hpp"\n'
        "int main() { std::fputs(LC_DOC(core_Zeta), stdout); }\n")
    done = subprocess.run([compiler, "-std=c++17", "-I", str(tmp_path / "generated"), "-o",
                           str(tmp_path / "main"), str(tmp_path / "main.cpp")],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    printed = subprocess.run([str(tmp_path / "main")], capture_output=True, text=True, check=True)
    assert printed.stdout == docs["core_Zeta"]


def test_the_real_localize_parts_header(docstrings, source_root, tmp_path):
    header = "localize/localize_parts.hpp"
    out = tmp_path / "docstrings.hpp"
    assert docstrings.main(["--root", source_root, "--out", str(out), header]) == 0
    docs = json.loads((tmp_path / "docstrings.hpp.json").read_text())
    with open(os.path.join(source_root, header), encoding="utf-8") as f:
        text = f.read()

    assert docs["localize_LocalizeParts"].startswith("Localizes the requested parts")
    assert docs["localize_LocalizePartsOptions"] == "Options of LocalizeParts."
    frame = re.search(r"^\s*std::string frame;\s*///< (.*)$", text, re.M).group(1)
    assert docs["localize_PartInstance_frame"] == frame
    # A trailing comment continued on the next line by an aligned `///<`.
    first, second = re.search(r"LocalizeOptions localize;\s*///< (.*)\n\s*///< (.*)", text).groups()
    assert docs["localize_LocalizePartsOptions_localize"] == f"{first} {second}"
    assert "localize_LocalizePartsOptions_use_roi" not in docs  # not documented
    assert all(key.startswith("localize_") for key in docs)
    assert len(docs) >= 40
