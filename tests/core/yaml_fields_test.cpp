#include "core/yaml_fields.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <string>

#include "core/error.hpp"

namespace lasercell::yaml {
namespace {

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const OptionError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(YamlFields, ReadsKnownFieldsAndKeepsDefaultsForAbsentOnes) {
  Fields top = Fields::Parse("a: 1.5\nn: 3\nsub: {flag: true, v: [1, 2, 3]}\nname: x\n", "t.yaml");
  double a = 0, missing = 7;
  int n = 0;
  std::string name;
  EXPECT_TRUE(top.Read("a", &a));
  EXPECT_FALSE(top.Read("missing", &missing));
  top.Read("n", &n);
  top.Read("name", &name);
  Fields sub = top.Sub("sub");
  bool flag = false;
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  sub.Read("flag", &flag);
  sub.Read("v", &v);
  sub.Done();
  top.Done();
  EXPECT_EQ(a, 1.5);
  EXPECT_EQ(missing, 7);
  EXPECT_EQ(n, 3);
  EXPECT_EQ(name, "x");
  EXPECT_TRUE(flag);
  EXPECT_EQ(v, Eigen::Vector3d(1, 2, 3));
}

TEST(YamlFields, ErrorsNameTheFileAndTheDottedField) {
  EXPECT_EQ(ErrorOf([] {
              Fields top = Fields::Parse("sub: {tpyo: 1}\n", "f.yaml");
              top.Sub("sub").Done();
            }),
            "f.yaml: unknown field 'sub.tpyo' (known fields here: )");
  EXPECT_EQ(ErrorOf([] {
              Fields top = Fields::Parse("x: abc\n", "f.yaml");
              double x;
              top.Read("x", &x);
            }),
            "f.yaml: field 'x' must be a number (got 'abc')");
  EXPECT_EQ(ErrorOf([] {
              Fields top = Fields::Parse("v: [1, 2]\n", "f.yaml");
              Eigen::Vector3d v;
              top.Read("v", &v);
            }),
            "f.yaml: field 'v' must list exactly 3 numbers (got 2)");
  EXPECT_EQ(ErrorOf([] {
              Fields top = Fields::Parse("{}", "f.yaml");
              double x;
              top.ReadRequired("x", &x);
            }),
            "f.yaml: field 'x' is required");
  EXPECT_EQ(ErrorOf([] {
              Fields top = Fields::Parse("format: other\n", "f.yaml");
              top.ExpectFormat("lasercell.thing", 1);
            }),
            "f.yaml: field 'format' is 'other', expected 'lasercell.thing'");
  EXPECT_NE(ErrorOf([] { Fields::Parse("a: [1, 2\n", "f.yaml"); }).find("f.yaml: not valid YAML"),
            std::string::npos);
  EXPECT_EQ(ErrorOf([] { Fields::Parse("- 1\n- 2\n", "f.yaml"); }),
            "f.yaml: the document must be a map of fields");
  EXPECT_EQ(ErrorOf([] {
              Fields top = Fields::Parse("x: .nan\n", "f.yaml");
              double x;
              top.Read("x", &x);
            }),
            "f.yaml: field 'x' must be a number (got '.nan')");
}

TEST(YamlFields, MissingFileIsAFileError) {
  EXPECT_THROW(Fields::Load("/nonexistent/options.yaml"), FileError);
}

}  // namespace
}  // namespace lasercell::yaml
