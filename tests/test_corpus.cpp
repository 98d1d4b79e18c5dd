// `squeeze mesh` over every real mesh of tests/data (issue 3): the written tetrahedral mesh is
// checked from the file itself (volumes, dihedral angles, face sharing, components, coverage,
// volume ratio), independently of the report, and the report is checked against it.
#include <gtest/gtest.h>

#include "meshing_test_util.h"
#include "squeeze/meshing/tet_io.h"

namespace {
using namespace sqt;

struct CorpusMesh {
  const char* file;
  int vertices, faces;  // as in tests/data/README.md
  bool closed, self_intersecting;
};

// tests/data/README.md.
const CorpusMesh kCorpus[] = {
    {"bunny00.off", 37706, 75408, true, false},
    {"ChineseDragon-10kv.off", 10000, 19994, false, true},
    {"elephant.off", 2775, 5558, true, false},
    {"sphere.off", 162, 320, true, false},
};

TEST(MeshCorpus, TableListsEveryMeshInTestData) {
  int listed = 0;
  for (const auto& e : fs::directory_iterator(SQUEEZE_TEST_DATA)) {
    if (e.path().extension() == ".md") continue;
    bool found = false;
    for (const auto& c : kCorpus) found |= e.path().filename() == c.file;
    EXPECT_TRUE(found) << e.path() << " is not covered by the corpus test";
    listed += found;
  }
  EXPECT_EQ(listed, static_cast<int>(std::size(kCorpus)));
}

/// Convex shells written by --shells (one OFF surface): split by face connectivity on indices
/// (each shell has its own vertices); a point is in a shell when it is on the inner side of all
/// its (outward) faces.
bool in_some_shell(const SurfaceMesh& shells, const std::vector<std::vector<int>>& faces_of_shell,
                   const Eigen::RowVector3d& p, double tol) {
  for (const auto& fs_ : faces_of_shell) {
    bool in = true;
    for (int f : fs_) {
      const Eigen::RowVector3d a = shells.V.row(shells.F(f, 0)), b = shells.V.row(shells.F(f, 1)),
                               c = shells.V.row(shells.F(f, 2));
      const Eigen::RowVector3d n = (b - a).cross(c - a);
      const double len = n.norm();
      if (len == 0) continue;
      if (n.dot(p - a) / len > tol) {
        in = false;
        break;
      }
    }
    if (in) return true;
  }
  return false;
}

void PrintTo(const CorpusMesh& c, std::ostream* os) { *os << c.file; }

class CorpusTest : public ::testing::TestWithParam<CorpusMesh> {};

TEST_P(CorpusTest, MeshMeetsTheContract) {
  const CorpusMesh& c = GetParam();
  TempDir dir(c.file);
  const fs::path input = data(c.file);
  const RunResult run = run_squeeze({"mesh", input.string(), "-o", "out.mesh", "--report", "r.json", "--shells",
                                     "shells.off"},
                                    dir.path(), 300);
  ASSERT_FALSE(run.crashed()) << "squeeze crashed or timed out, code " << run.code << "\n" << run.err;
  ASSERT_EQ(run.code, 0) << run.err;
  ASSERT_TRUE(fs::exists(dir / "out.mesh"));
  ASSERT_TRUE(fs::exists(dir / "r.json"));
  ASSERT_TRUE(fs::exists(dir / "shells.off"));
  EXPECT_TRUE(temporaries_in(dir.path()).empty());

  const SurfaceMesh surface = read_off(input);
  ASSERT_EQ(surface.V.rows(), c.vertices);
  ASSERT_EQ(surface.F.rows(), c.faces);
  const InputTruth truth = truth_of(surface, c.closed);
  const TetMesh tets = squeeze::load_tet_mesh(dir / "out.mesh");
  const TetFacts facts = expect_mesh_contract(tets, truth, c.file);

  const nlohmann::json report = nlohmann::json::parse(read_text(dir / "r.json"));
  expect_report(report, facts, truth, c.file);
  EXPECT_EQ(report["input"]["vertices"], c.vertices);
  EXPECT_EQ(report["input"]["faces"], c.faces);
  EXPECT_EQ(report["input"]["closed"], c.closed);
  EXPECT_EQ(report["input"]["self_intersecting"], c.self_intersecting);
  EXPECT_EQ(report["input"]["components"], truth.components);
  // The report's coverage matches ours (different point location code, same definition).
  const Coverage cov = coverage(tets, facts.boundary, truth.points, 0.005 * diagonal(truth.points));
  EXPECT_NEAR(report["coverage"]["inside_fraction"].get<double>(), cov.inside, 0.01);
  EXPECT_NEAR(report["coverage"]["within_tolerance_fraction"].get<double>(), cov.covered, 0.01);

  // The shells: as many as the report says, and together they hold every input vertex
  // (decompose.h), within a hair of the diagonal.
  const SurfaceMesh shells = read_off(dir / "shells.off");
  DisjointSets ds(static_cast<size_t>(shells.V.rows()));
  for (Eigen::Index f = 0; f < shells.F.rows(); ++f) {
    ds.unite(shells.F(f, 0), shells.F(f, 1));
    ds.unite(shells.F(f, 0), shells.F(f, 2));
  }
  std::map<int, std::vector<int>> by_root;
  for (Eigen::Index f = 0; f < shells.F.rows(); ++f) by_root[ds.find(shells.F(f, 0))].push_back(static_cast<int>(f));
  std::vector<std::vector<int>> faces_of_shell;
  for (auto& [root, fs_] : by_root) faces_of_shell.push_back(fs_);
  EXPECT_EQ(static_cast<double>(faces_of_shell.size()), report["decomposition"]["hulls"].get<double>());
  const double tol = 1e-7 * diagonal(truth.points);
  int outside = 0;
  for (Eigen::Index i = 0; i < truth.points.rows(); ++i)
    outside += !in_some_shell(shells, faces_of_shell, truth.points.row(i), tol);
  EXPECT_EQ(outside, 0) << "input vertices in no convex shell";
}

INSTANTIATE_TEST_SUITE_P(MeshCorpus, CorpusTest, ::testing::ValuesIn(kCorpus),
                         [](const ::testing::TestParamInfo<CorpusMesh>& i) {
                           std::string n = fs::path(i.param.file).stem().string();
                           for (char& ch : n)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return n;
                         });

}  // namespace
