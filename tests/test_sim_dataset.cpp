// The dataset layout (docs/dataset.md): writer/reader round trip, reader
// errors, and the builder's determinism, resume and split rules.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "base/error.h"
#include "engine/io/image_mat.h"
#include "engine/sim/dataset.h"
#include "engine/sim/dataset_builder.h"
#include "engine/sim/everyday_shapes.h"
#include "engine/sim/shapes.h"
#include "tests/harness.h"
#include "tests/io_test_util.h"

namespace fs = std::filesystem;
using namespace vtloc;
using namespace vtloc::sim;
using vtloc::test::require_error;

namespace {

std::string slurp(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
}

fs::path fresh_dir(const std::string& name) {
    fs::path d = vtloc::test::temp_path(name);
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

// A hand-made one-object dataset with three touches.
fs::path write_small_dataset(const std::string& name) {
    fs::path root = fresh_dir(name);
    fs::create_directories(root / "objects" / "cube");
    ObjectRecord o;
    o.name = "cube";
    o.subset = "uniform";
    o.dn_share = 0.9;
    o.object_split = "seen";
    o.n_points = 4;
    o.points = HostTensor({4, 6}, {0, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 1, 1, 1, 0, 0, 0, 1});
    write_object_json((root / "objects/cube/object.json").string(), o);
    write_points_csv((root / "objects/cube/points.csv").string(), o.points);
    std::vector<TouchRecord> t(3);
    const char* splits[] = {"test", "train", "test"};
    for (int i = 0; i < 3; ++i) {
        t[size_t(i)].id = i;
        t[size_t(i)].split = splits[i];
        t[size_t(i)].order = 2 - i;
        t[size_t(i)].image = "touches/000" + std::to_string(i) + ".png";
        t[size_t(i)].contact = {double(i), 0.5, 0.25};
        t[size_t(i)].motion = {0.1 * i, 0, 0};
    }
    write_touches_csv((root / "objects/cube/touches.csv").string(), t);
    Dataset d;
    d.seed = 7;
    d.n_points = 4;
    d.objects.push_back(o);
    write_dataset_json((root / "dataset.json").string(), d);
    return root;
}

}  // namespace

TEST_CASE("dataset: written files read back", "[sim]") {
    fs::path root = write_small_dataset("ds_roundtrip");
    Dataset d = read_dataset(root.string());
    REQUIRE(d.objects.size() == 1);
    CHECK(d.seed == 7);
    CHECK(d.sensor.width == 160);
    const ObjectRecord& o = d.objects[0];
    CHECK(o.subset == "uniform");
    CHECK(o.object_split == "seen");
    REQUIRE(o.points.shape == Shape{4, 6});
    CHECK(o.points.data[6] == 1.0f);
    REQUIRE(o.touches.size() == 3);
    CHECK(o.touches[2].order == 0);
    CHECK(o.touches[1].motion[0] == Approx(0.1));
    CHECK(o.touches[0].rel_R[4] == 1.0);
    HostTensor c = o.candidates();
    REQUIRE(c.shape == Shape{2, 3});  // the two test touches, in id order
    CHECK(c.data[3] == 2.0f);
    CHECK_FALSE(o.has_mesh);
    // No temporary file is left behind.
    for (auto& e : fs::recursive_directory_iterator(root)) CHECK(e.path().extension() != ".tmp");
}

TEST_CASE("dataset: reader errors name the file", "[sim]") {
    fs::path empty = fresh_dir("ds_empty");
    require_error([&] { read_dataset(empty.string()); }, {"ds_empty", "not a dataset"});
    require_error([&] { read_dataset((empty / "nope").string()); }, {"not a folder"});

    fs::path root = write_small_dataset("ds_bad_format");
    std::string j = slurp(root / "dataset.json");
    j.replace(j.find("vtloc-synth/1"), 13, "vtloc-synth/9");
    write_file_atomic((root / "dataset.json").string(), j);
    require_error([&] { read_dataset(root.string()); }, {"dataset.json", "vtloc-synth/9"});

    root = write_small_dataset("ds_bad_number");
    fs::path tc = root / "objects/cube/touches.csv";
    std::string t = slurp(tc);
    t.replace(t.find(",0.5,"), 5, ",abc,");
    write_file_atomic(tc.string(), t);
    require_error([&] { read_dataset(root.string()); }, {"touches.csv:2", "cy", "abc"});

    // Fuzzer finding (tests/fuzz, fuzz_dataset): an optional field of the wrong type
    // escaped as the JSON library's exception instead of a one-line error.
    root = write_small_dataset("ds_seed_object");
    j = slurp(root / "dataset.json");
    j.replace(j.find("\"seed\""), 6, "\"seed\": {}, \"_seed\"");
    write_file_atomic((root / "dataset.json").string(), j);
    require_error([&] { read_dataset(root.string()); }, {"dataset.json", "field 'seed' has the wrong type"});

    // Fuzzer finding (fuzz_dataset, once UBSan halted the fuzzer): a float or an
    // out-of-range integer where an integer field belongs was cast by the JSON
    // library, undefined behaviour; now a one-line error.
    for (const char* bad : {"1.5e39", "3000000000", "12.5", "-1"}) {
        root = write_small_dataset("ds_n_points_range");
        j = slurp(root / "dataset.json");
        const size_t at = j.find("\"n_points\"");
        REQUIRE(at != std::string::npos);
        j.replace(at, j.find_first_of(",}", at) - at, std::string("\"n_points\": ") + bad);
        write_file_atomic((root / "dataset.json").string(), j);
        INFO("n_points " << bad);
        if (std::string(bad) == "-1")  // in range of int: refused by the reader's own check
            require_error([&] { read_dataset(root.string()); }, {"dataset.json", "'n_points' must be >= 1, got -1"});
        else
            require_error([&] { read_dataset(root.string()); }, {"dataset.json", "'n_points' must be an integer in the range"});
    }

    root = write_small_dataset("ds_missing_points");
    fs::remove(root / "objects/cube/points.csv");
    require_error([&] { read_dataset(root.string()); }, {"points.csv", "cannot read"});

    root = write_small_dataset("ds_missing_column");
    fs::path pc = root / "objects/cube/points.csv";
    std::string p = slurp(pc);
    p.replace(0, p.find('\n'), "x,y,z,nx,ny,nw");
    write_file_atomic(pc.string(), p);
    require_error([&] { read_dataset(root.string()); }, {"points.csv", "missing column 'nz'"});
}

namespace {

// Small, quick builds: 10 contacts, 128 points, one thread, into a fresh folder.
BuildOptions small_build(const std::string& dir, int extra, int extra_views = 1) {
    BuildOptions o;
    o.contacts = 10;
    o.extra = extra;
    o.extra_views = extra_views;
    o.n_points = 128;
    o.seed = 5;
    o.threads = 1;
    o.out = fresh_dir(dir).string();
    return o;
}

}  // namespace

TEST_CASE("dataset builder: deterministic, resumable, split as documented", "[sim]") {
    BuildOptions o = small_build("ds_build_a", 3);
    std::vector<ObjectSource> objs = {{"shape:sphere", 60.0}, {"shape:box", 80.0}, {"shape:comb_fine", {}}};
    BuildReport ra = build_dataset(objs, o);
    CHECK(ra.objects == 3);
    CHECK(ra.resumed == 0);
    o.out = fresh_dir("ds_build_b").string();
    o.threads = 2;  // another thread count must not change a byte
    build_dataset(objs, o);

    Dataset a = read_dataset((fs::path(vtloc::test::temp_path("ds_build_a"))).string());
    REQUIRE(a.objects.size() == 3);
    for (const ObjectRecord& ob : a.objects) {
        INFO(ob.name);
        fs::path fa = ob.folder, fb = fs::path(vtloc::test::temp_path("ds_build_b")) / "objects" / ob.name;
        CHECK(slurp(fa / "touches.csv") == slurp(fb / "touches.csv"));
        CHECK(slurp(fa / "points.csv") == slurp(fb / "points.csv"));
        CHECK(slurp(fa / "touches/0003.png") == slurp(fb / "touches/0003.png"));
        // 7:3 split of 10 contacts, 3 extra touches, ids in order.
        CHECK(ob.touches_of("test").size() == 3);
        CHECK(ob.touches_of("train").size() == 7);
        CHECK(ob.touches_of("extra").size() == 3);
        // Collection order is a permutation of the train + test touches.
        std::vector<int> orders;
        for (const auto& t : ob.touches)
            if (t.split != "extra") orders.push_back(t.order);
        std::sort(orders.begin(), orders.end());
        for (size_t i = 0; i < orders.size(); ++i) CHECK(orders[i] == int(i));
        // Extra touches keep 2 mm from every test contact.
        for (const auto* e : ob.touches_of("extra"))
            for (const auto* t : ob.touches_of("test")) {
                double d2 = 0;
                for (int k = 0; k < 3; ++k) d2 += (e->contact[size_t(k)] - t->contact[size_t(k)]) * (e->contact[size_t(k)] - t->contact[size_t(k)]);
                CHECK(d2 >= 4.0);
            }
        CHECK(ob.has_mesh);
        CHECK(ob.has_background);
    }
    // The comb is non-uniform, the sphere uniform (SPEC section 5), and the
    // object split puts one of the two uniform objects among the unseen.
    for (const ObjectRecord& ob : a.objects) {
        if (ob.name == "sphere") CHECK(ob.subset == "uniform");
        if (ob.name == "comb_fine") CHECK(ob.subset == "non-uniform");
    }

    // Resume: a deleted object is rebuilt identically, the others are kept.
    fs::path comb = fs::path(vtloc::test::temp_path("ds_build_a")) / "objects" / "comb_fine";
    std::string before = slurp(comb / "touches.csv");
    fs::remove_all(comb);
    o.out = vtloc::test::temp_path("ds_build_a");
    o.threads = 1;
    BuildReport rr = build_dataset(objs, o);
    CHECK(rr.resumed == 2);
    CHECK(slurp(comb / "touches.csv") == before);

    // Pinned splits: kept as given; the unpinned objects split among themselves.
    std::vector<ObjectSource> pinned = objs;
    for (ObjectSource& s : pinned) s.split = "unseen";
    pinned[2].split.clear();  // the comb, alone in its subset: never unseen then
    CHECK(build_dataset(pinned, o).resumed == 3);
    for (const ObjectRecord& ob : read_dataset(o.out).objects) CHECK(ob.object_split == (ob.name == "comb_fine" ? "seen" : "unseen"));
    pinned[0].split = "seen", pinned[1].split = "seen";
    build_dataset(pinned, o);
    for (const ObjectRecord& ob : read_dataset(o.out).objects) CHECK(ob.object_split == "seen");

    // Other options into the same folder are refused.
    o.seed = 6;
    require_error([&] { build_dataset(objs, o); }, {"ds_build_a", "other options"});
}

TEST_CASE("dataset builder: --extra-views renders each extra contact several times", "[sim]") {
    BuildOptions o = small_build("ds_build_views", 9, 3);
    build_dataset({{"shape:box", 80.0}}, o);
    Dataset d = read_dataset(o.out);
    REQUIRE(d.objects.size() == 1);
    const auto extra = d.objects[0].touches_of("extra");
    REQUIRE(extra.size() == 9);
    // Three contacts, three renders each: one place (the tilt moves the contact
    // by at most a few tenths of a mm), other spins and presses.
    for (size_t g = 0; g < 9; g += 3)
        for (size_t v = 1; v < 3; ++v) {
            const auto &a = *extra[g], &b = *extra[g + v];
            double d2 = 0;
            for (int k = 0; k < 3; ++k) d2 += (a.contact[size_t(k)] - b.contact[size_t(k)]) * (a.contact[size_t(k)] - b.contact[size_t(k)]);
            CHECK(d2 < 1.0);
            CHECK(a.spin_deg != b.spin_deg);
            CHECK(a.press_mm != b.press_mm);
        }
    double d01 = 0;
    for (int k = 0; k < 3; ++k) d01 += (extra[0]->contact[size_t(k)] - extra[3]->contact[size_t(k)]) * (extra[0]->contact[size_t(k)] - extra[3]->contact[size_t(k)]);
    CHECK(d01 > 1.0);  // the next group is another place
    // A dataset built with one view per contact is not resumed with three.
    o.extra_views = 1;
    require_error([&] { build_dataset({{"shape:box", 80.0}}, o); }, {"ds_build_views", "other options"});
}

TEST_CASE("dataset builder: object list errors", "[sim]") {
    fs::path d = fresh_dir("ds_list");
    std::ofstream(d / "list.txt") << "# comment\nshape:sphere 50\nfoo.off abc\n";
    require_error([&] { read_object_list((d / "list.txt").string()); }, {"list.txt:3", "abc"});
    std::ofstream(d / "list2.txt") << "# nothing\n";
    require_error([&] { read_object_list((d / "list2.txt").string()); }, {"list2.txt", "no objects"});
    std::ofstream(d / "list3.txt") << "shape:sphere 50\nmeshes/a.off\n";
    auto l = read_object_list((d / "list3.txt").string(), "/data");
    REQUIRE(l.size() == 2);
    CHECK(*l[0].scale_mm == 50.0);
    CHECK(l[1].source == "/data/meshes/a.off");
    CHECK_FALSE(l[1].scale_mm);
    CHECK(l[1].split.empty());
    std::ofstream(d / "list4.txt") << "shape:sphere 50 unseen\nshape:box seen # pinned\n";
    auto p = read_object_list((d / "list4.txt").string());
    REQUIRE(p.size() == 2);
    CHECK((*p[0].scale_mm == 50.0 && p[0].split == "unseen"));
    CHECK((!p[1].scale_mm && p[1].split == "seen"));
    std::ofstream(d / "list5.txt") << "shape:sphere seen unseen\n";
    require_error([&] { read_object_list((d / "list5.txt").string()); }, {"list5.txt:1", "twice"});
    std::ofstream(d / "list6.txt") << "shape:sphere\nshape:box seen 50\n";
    require_error([&] { read_object_list((d / "list6.txt").string()); }, {"list6.txt:2", "[seen|unseen]"});
    std::ofstream(d / "list7.txt") << "shape:sphere 50 60\n";
    require_error([&] { read_object_list((d / "list7.txt").string()); }, {"list7.txt:1", "expected"});
    std::ofstream(d / "list8.txt") << "a.off 50 half-turn:y seen\nb.off half-turn:x\n";
    auto h = read_object_list((d / "list8.txt").string());
    REQUIRE(h.size() == 2);
    CHECK((h[0].half_turn == 'y' && *h[0].scale_mm == 50.0 && h[0].split == "seen"));
    CHECK((h[1].half_turn == 'x' && !h[1].scale_mm && h[1].split.empty()));
    std::ofstream(d / "list9.txt") << "a.off half-turn:w\n";
    require_error([&] { read_object_list((d / "list9.txt").string()); }, {"list9.txt:1", "half-turn:w", "x, y or z"});
    std::ofstream(d / "list10.txt") << "shape:box half-turn:z\n";
    require_error([&] { read_object_list((d / "list10.txt").string()); }, {"list10.txt:1", "declares its own"});
    std::ofstream(d / "list11.txt") << "a.off half-turn:z half-turn:x\n";
    require_error([&] { read_object_list((d / "list11.txt").string()); }, {"list11.txt:1", "twice"});
    std::ofstream(d / "list12.txt") << "a.off seen half-turn:z\n";
    require_error([&] { read_object_list((d / "list12.txt").string()); }, {"list12.txt:1", "expected"});
}

namespace {

// A procedural shape as an OFF file (the list's mesh-file path).
std::string write_off(const fs::path& path, const std::string& shape) {
    const io::TriangleMesh m = sim::make_shape(shape);
    std::ofstream f(path);
    f << "OFF\n" << m.vertex_count() << " " << m.triangle_count() << " 0\n";
    for (size_t i = 0; i < m.vertex_count(); ++i)
        f << m.positions[3 * i] << " " << m.positions[3 * i + 1] << " " << m.positions[3 * i + 2] << "\n";
    for (size_t t = 0; t < m.triangle_count(); ++t)
        f << "3 " << m.triangles[3 * t] << " " << m.triangles[3 * t + 1] << " " << m.triangles[3 * t + 2] << "\n";
    return path.string();
}

}  // namespace

TEST_CASE("dataset builder: a mesh file's half turn is its symmetry, and is checked", "[sim][symmetry]") {
    BuildOptions o = small_build("ds_build_half_turn", 0);
    o.contacts = 2;
    const fs::path dir(o.out);
    // The comb's outline mirrors about the middle of its length: a half turn about y holds.
    ObjectSource comb{write_off(dir / "comb.off", "comb_coarse"), 180.0};
    comb.half_turn = 'y';
    build_dataset({comb}, o);
    const Dataset ds = read_dataset(o.out);
    REQUIRE(ds.objects.size() == 1);
    const sim::Symmetry& s = ds.objects[0].symmetry;
    CHECK((s.order == 2 && s.axis == sim::Vec3d{0, 1, 0} && !s.flip));
    // The same comb turned about x would hang its teeth above its back: refused, naming the file.
    BuildOptions o2 = small_build("ds_build_half_turn_bad", 0);
    o2.contacts = 2;
    ObjectSource bad{write_off(fs::path(o2.out) / "comb_x.off", "comb_coarse"), 180.0};
    bad.half_turn = 'x';
    require_error([&] { build_dataset({bad}, o2); }, {"comb_x.off", "half-turn:x", "does not hold"});
}

TEST_CASE("dataset builder: the default object list pins the first benchmark's split and adds the everyday objects", "[sim]") {
    const auto l = read_object_list(std::string(VTLOC_SOURCE_DIR) + "/data/synth/objects.txt", "/meshes");
    REQUIRE(l.size() == 68);
    int unseen = 0;
    for (size_t i = 0; i < 43; ++i) {
        INFO(l[i].source);
        CHECK(!l[i].split.empty());  // moving one would put a trained-on object among the unknown
        unseen += l[i].split == "unseen";
    }
    CHECK(unseen == 13);
    std::set<std::string> listed;
    for (size_t i = 43; i < l.size(); ++i) {
        CHECK(l[i].split.empty());
        listed.insert(l[i].source);
    }
    for (const sim::EverydayShape& e : sim::everyday_shapes()) CHECK(listed.count(std::string("shape:") + e.name) == 1);
}

TEST_CASE("dataset builder: --indentation writes each touch's ground-truth indentation", "[sim]") {
    BuildOptions o = small_build("ds_build_depth", 4);
    o.indentation = true;
    build_dataset({{"shape:cone", 60.0}}, o);
    Dataset d = read_dataset(o.out);
    REQUIRE(d.objects.size() == 1);
    const ObjectRecord& ob = d.objects[0];
    REQUIRE(ob.touches.size() == 14);
    for (const TouchRecord& t : ob.touches) {
        fs::path p = fs::path(ob.folder) / t.image;
        p.replace_extension(".depth.png");
        INFO(p.string());
        cv::Mat m = vtloc::io::read_mat(p.string());
        REQUIRE(m.type() == CV_16UC1);
        cv::Mat frame = vtloc::io::read_mat((fs::path(ob.folder) / t.image).string());
        CHECK(m.size() == frame.size());
        double hi = 0;
        cv::minMaxLoc(m, nullptr, &hi);
        // Micrometres: some of the gel is pressed in, never deeper than the
        // press itself (the gel starts at first contact).
        CHECK(hi > 50);
        CHECK(hi <= 1000 * t.press_mm + 1);
    }
    // A dataset built without the maps is not resumed with them.
    o.indentation = false;
    require_error([&] { build_dataset({{"shape:cone", 60.0}}, o); }, {"ds_build_depth", "other options"});
}
