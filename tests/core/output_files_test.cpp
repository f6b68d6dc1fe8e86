// AtomicFile and OutputDirectory: combabc never deletes, truncates or replaces a file or
// directory it did not create, unless asked to with overwrite, and then only that path.
#include "combabc/core/output_files.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "combabc/core/error.hpp"
#include "support/test_support.hpp"

namespace combabc {
namespace {

namespace fs = std::filesystem;
using testing::TempFolder;

std::string Read(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void Write(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

// The names in a directory, so a test can assert that nothing else appeared or vanished.
std::set<std::string> Listing(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) {
    names.insert(entry.path().filename().string());
  }
  return names;
}

ErrorKind KindOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& error) {
    return error.kind();
  }
  ADD_FAILURE() << "no combabc::Error";
  return ErrorKind::kSoftware;
}

class OutputFilesTest : public ::testing::Test {
 protected:
  const TempFolder folder_{"output-files"};
  const fs::path dir_ = folder_.path();
};

TEST_F(OutputFilesTest, AtomicFileCreatesAndRefusesToReplaceUnlessAsked) {
  const fs::path target = dir_ / "profile.csv";
  WriteFileAtomically(target.string(), "one\n", /*overwrite=*/false);
  EXPECT_EQ(Read(target), "one\n");
  EXPECT_EQ(KindOf([&] { WriteFileAtomically(target.string(), "two\n", false); }),
            ErrorKind::kCantCreate);
  EXPECT_EQ(Read(target), "one\n") << "an existing file was replaced without overwrite";
  WriteFileAtomically(target.string(), "three\n", /*overwrite=*/true);
  EXPECT_EQ(Read(target), "three\n");
  EXPECT_EQ(Listing(dir_), std::set<std::string>{"profile.csv"}) << "temporary left behind";
}

TEST_F(OutputFilesTest, AtomicFileNeverFollowsAPlantedSymlink) {
  const fs::path victim = dir_ / "victim.txt";
  Write(victim, "precious\n");
  const fs::path target = dir_ / "out.csv";
  // The old implementation wrote through "<target>.tmp"; a link there must stay untouched.
  fs::create_symlink(victim, dir_ / "out.csv.tmp");
  WriteFileAtomically(target.string(), "data\n", false);
  EXPECT_EQ(Read(victim), "precious\n");
  EXPECT_EQ(Read(target), "data\n");
  EXPECT_TRUE(fs::is_symlink(dir_ / "out.csv.tmp"));

  // A symlink at the target itself: refused without overwrite; with it, the link (the path the
  // user named) is replaced, never the file it points to.
  const fs::path link = dir_ / "link.csv";
  fs::create_symlink(victim, link);
  EXPECT_EQ(KindOf([&] { WriteFileAtomically(link.string(), "x\n", false); }),
            ErrorKind::kCantCreate);
  WriteFileAtomically(link.string(), "x\n", true);
  EXPECT_FALSE(fs::is_symlink(link));
  EXPECT_EQ(Read(link), "x\n");
  EXPECT_EQ(Read(victim), "precious\n");
}

TEST_F(OutputFilesTest, AtomicFileNeverReplacesADirectoryAndCleansUpWhenAbandoned) {
  fs::create_directories(dir_ / "results" / "inner");
  EXPECT_EQ(KindOf([&] { WriteFileAtomically((dir_ / "results").string(), "x", true); }),
            ErrorKind::kCantCreate);
  EXPECT_TRUE(fs::is_directory(dir_ / "results" / "inner"));
  {
    AtomicFile abandoned((dir_ / "never.csv").string(), false);
    abandoned.out() << "half";
  }
  EXPECT_EQ(Listing(dir_), std::set<std::string>{"results"});
}

TEST_F(OutputFilesTest, NewDirectoryIsCreatedWithAManifest) {
  const fs::path out = dir_ / "export";
  {
    OutputDirectory directory(out.string(), false);
    directory.Add("a.csv") << "a";
    directory.Add("b.csv") << "b";
    directory.Commit();
  }
  EXPECT_EQ(Listing(out), (std::set<std::string>{"a.csv", "b.csv", ".combabc-manifest"}));
  EXPECT_NE(Read(out / ".combabc-manifest").find("\na.csv\nb.csv\n"), std::string::npos);
}

// The NetCDF export: a helper process reads staged files and writes an added one by path.
TEST_F(OutputFilesTest, StagedFilesCanBeReadAndWrittenByPathAndDiscarded) {
  const fs::path out = dir_ / "export";
  {
    OutputDirectory directory(out.string(), false);
    directory.Add("a.csv") << "first,";
    const std::string staged = directory.StagedPath("a.csv");
    EXPECT_EQ(Read(staged), "first,");
    EXPECT_EQ(fs::path(staged).parent_path(), out);
    directory.Add("b.nc");
    Write(directory.StagedPath("b.nc"), "written by another process");
    directory.Add("c.nc");
    EXPECT_TRUE(directory.Has("c.nc"));
    directory.Discard("c.nc");
    EXPECT_FALSE(directory.Has("c.nc"));  // what the export asks before naming curves.csv
    EXPECT_FALSE(directory.Has("never.csv"));
    EXPECT_EQ(KindOf([&] { directory.StagedPath("c.nc"); }), ErrorKind::kSoftware);
    EXPECT_FALSE(fs::exists(out / "a.csv"));  // nothing appears before Commit
    directory.Commit();
  }
  EXPECT_EQ(Read(out / "a.csv"), "first,");
  EXPECT_EQ(Read(out / "b.nc"), "written by another process");
  EXPECT_EQ(Listing(out), (std::set<std::string>{"a.csv", "b.nc", ".combabc-manifest"}));
}

TEST_F(OutputFilesTest, UncommittedDirectoryLeavesNothingBehind) {
  {
    OutputDirectory directory((dir_ / "export").string(), false);
    directory.Add("a.csv") << "a";
  }
  EXPECT_TRUE(fs::is_empty(dir_)) << "a directory combabc created and did not fill remains";
  fs::create_directories(dir_ / "mine");
  {
    OutputDirectory directory((dir_ / "mine").string(), false);
    directory.Add("a.csv") << "a";
  }
  EXPECT_TRUE(fs::is_directory(dir_ / "mine")) << "the user's empty directory was removed";
  EXPECT_TRUE(fs::is_empty(dir_ / "mine"));
}

TEST_F(OutputFilesTest, LeftoversOfAKilledCommandDoNotMakeADirectoryForeign) {
  const fs::path out = dir_ / "export";
  fs::create_directories(out);
  Write(out / ".combabc-tmp-k1ll3d00-waves.csv", "half");
  OutputDirectory::Check(out.string(), false);
  Write(out / "user.txt", "x");
  EXPECT_EQ(KindOf([&] { OutputDirectory::Check(out.string(), false); }), ErrorKind::kCantCreate);
}

// Issue 35 (E15): what a signal handler removes before the signal ends the process (no
// destructor runs then): every live temporary, then an uncommitted directory combabc created.
TEST_F(OutputFilesTest, PendingOutputsAreRemovedForASignalHandler) {
  AtomicFile file((dir_ / "single.csv").string(), false);
  file.out() << "half";
  file.Flush();
  OutputDirectory directory((dir_ / "export").string(), false);
  directory.Add("a.csv") << "a";
  const std::string staged = directory.StagedPath("a.csv");
  ASSERT_TRUE(fs::exists(file.temporary_path()));
  ASSERT_TRUE(fs::exists(staged));
  RemovePendingOutputs();
  EXPECT_FALSE(fs::exists(file.temporary_path()));
  EXPECT_FALSE(fs::exists(staged));
  EXPECT_FALSE(fs::exists(dir_ / "export"));
  // A committed file or directory is no longer pending.
  AtomicFile kept((dir_ / "kept.csv").string(), false);
  kept.Commit();
  {
    OutputDirectory done((dir_ / "done").string(), false);
    done.Add("b.csv") << "b";
    done.Commit();
  }
  RemovePendingOutputs();
  EXPECT_TRUE(fs::exists(dir_ / "kept.csv"));
  EXPECT_TRUE(fs::exists(dir_ / "done/b.csv"));
}

// Issue 35 (E15): a temporary a killed or interrupted command left in combabc's directory (with a
// manifest, or holding only temporaries) is removed by the next command that opens it, once its
// process is gone; one of a live process, a name combabc does not make, and anything in a
// directory that is not combabc's are left alone.
TEST_F(OutputFilesTest, StaleTemporariesOfEndedProcessesAreRemovedFromCombabcsDirectories) {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ASSERT_GT(child, 0);
  ASSERT_EQ(::waitpid(child, nullptr, 0), child);  // reaped: no process has that id now
  const std::string prefix = OutputDirectory::kTemporaryPrefix;
  const std::string dead = prefix + std::to_string(child) + "-abcdefgh-waves.csv";
  const std::string live = prefix + std::to_string(::getppid()) + "-abcdefgh-waves.csv";
  const std::string unknown = prefix + "k1ll3d00-waves.csv";
  for (const char* folder : {"owned", "leftovers", "foreign"}) {
    fs::create_directories(dir_ / folder);
    for (const std::string& name : {dead, live, unknown}) Write(dir_ / folder / name, "half");
  }
  {
    OutputDirectory owned((dir_ / "owned").string(), false);
    owned.Add("a.csv") << "a";
    owned.Commit();
  }
  Write(dir_ / "owned/extra.txt", "the user's");
  Write(dir_ / "foreign/notes.txt", "the user's");
  { OutputDirectory again((dir_ / "owned").string(), false); }
  { OutputDirectory leftovers((dir_ / "leftovers").string(), false); }
  { OutputDirectory foreign((dir_ / "foreign").string(), true); }
  EXPECT_EQ(Listing(dir_ / "owned"),
            (std::set<std::string>{live, unknown, "a.csv", "extra.txt", ".combabc-manifest"}));
  EXPECT_EQ(Listing(dir_ / "leftovers"), (std::set<std::string>{live, unknown}));
  EXPECT_EQ(Listing(dir_ / "foreign"), (std::set<std::string>{dead, live, unknown, "notes.txt"}));
}

TEST_F(OutputFilesTest, ForeignDirectoryIsRefusedAndLeftAlone) {
  // What `report -o .` met: the user's working directory.
  Write(dir_ / "thesis.tex", "years of work");
  Write(dir_ / "a.csv", "the user's own a.csv");
  const auto before = Listing(dir_);
  EXPECT_EQ(KindOf([&] { OutputDirectory::Check(dir_.string(), false); }), ErrorKind::kCantCreate);
  EXPECT_EQ(KindOf([&] { OutputDirectory directory(dir_.string() + "/", false); }),
            ErrorKind::kCantCreate);
  EXPECT_EQ(Listing(dir_), before);
  // A file is not a directory, with or without overwrite.
  EXPECT_EQ(KindOf([&] { OutputDirectory directory((dir_ / "thesis.tex").string(), true); }),
            ErrorKind::kCantCreate);
  EXPECT_EQ(Read(dir_ / "thesis.tex"), "years of work");
}

TEST_F(OutputFilesTest, OverwriteReplacesOnlySameNamedFiles) {
  Write(dir_ / "thesis.tex", "years of work");
  Write(dir_ / "a.csv", "the user's own a.csv");
  OutputDirectory::Check(dir_.string(), true);
  {
    OutputDirectory directory(dir_.string(), /*overwrite=*/true);
    directory.Add("a.csv") << "combabc a";
    directory.Add("b.csv") << "combabc b";
    directory.Commit();
  }
  EXPECT_EQ(Read(dir_ / "thesis.tex"), "years of work");
  EXPECT_EQ(Read(dir_ / "a.csv"), "combabc a");
  EXPECT_EQ(Listing(dir_),
            (std::set<std::string>{"thesis.tex", "a.csv", "b.csv", ".combabc-manifest"}));
}

TEST_F(OutputFilesTest, RewriteReplacesOnlyWhatTheManifestLists) {
  const fs::path out = dir_ / "report";
  {
    OutputDirectory directory(out.string(), false);
    directory.Add("wave_1.png") << "old 1";
    directory.Add("wave_2.png") << "old 2";
    directory.Commit();
  }
  Write(out / "notes.txt", "the user's notes");
  {
    OutputDirectory directory(out.string(), false);  // has a manifest: no overwrite needed
    directory.Add("wave_1.png") << "new 1";
    directory.Commit();
  }
  EXPECT_EQ(Read(out / "wave_1.png"), "new 1");
  EXPECT_FALSE(fs::exists(out / "wave_2.png")) << "combabc's own stale file should go";
  EXPECT_EQ(Read(out / "notes.txt"), "the user's notes");
  EXPECT_EQ(Read(out / ".combabc-manifest").find("wave_2.png"), std::string::npos);

  // A file the manifest does not list, where combabc now wants to write: refused, untouched,
  // whether it was there before the files were staged or appeared while they were written.
  Write(out / "summary.png", "the user's figure");
  {
    OutputDirectory directory(out.string(), false);
    directory.Add("wave_1.png") << "newer 1";
    EXPECT_EQ(KindOf([&] { directory.Add("summary.png"); }), ErrorKind::kCantCreate);
    directory.Add("overview.png") << "combabc overview";
    Write(out / "overview.png", "the user's overview");
    EXPECT_EQ(KindOf([&] { directory.Commit(); }), ErrorKind::kCantCreate);
  }
  EXPECT_EQ(Read(out / "overview.png"), "the user's overview");
  EXPECT_EQ(Read(out / "summary.png"), "the user's figure");
  EXPECT_EQ(Read(out / "wave_1.png"), "new 1") << "a refused commit changed a file";
  EXPECT_EQ(Listing(out),
            (std::set<std::string>{
                "wave_1.png", "notes.txt", "summary.png", "overview.png", ".combabc-manifest"}));
}

TEST_F(OutputFilesTest, ManifestCannotNameAnythingOutsideTheDirectory) {
  const fs::path out = dir_ / "report";
  fs::create_directories(out);
  Write(dir_ / "outside.txt", "keep");
  fs::create_directories(out / "sub");
  Write(out / "sub" / "inside.txt", "keep");
  Write(out / ".combabc-manifest", "../outside.txt\nsub/inside.txt\nsub\n..\n");
  {
    OutputDirectory directory(out.string(), false);
    directory.Add("a.png") << "a";
    directory.Commit();
  }
  EXPECT_EQ(Read(dir_ / "outside.txt"), "keep");
  EXPECT_EQ(Read(out / "sub" / "inside.txt"), "keep");
  EXPECT_TRUE(fs::exists(out / "a.png"));
}

// --overwrite replaces regular files only (issue D1): renaming a file over /dev/null as root
// replaced the device. A character device is written into, as cp and tee do; the device here is
// reached through a symlink in the test's own folder, so that a regression renames over the link
// and never over /dev/null itself.
TEST_F(OutputFilesTest, OverwriteWritesIntoACharacterDeviceAndNeverReplacesIt) {
  const fs::path link = dir_ / "null.csv";
  fs::create_symlink("/dev/null", link);
  for (const bool replace : {false, true}) {
    AtomicFile file(link.string(), replace);
    file.out() << "position_m,w_m\n";
    file.Commit();
    EXPECT_TRUE(fs::is_symlink(link)) << "replace = " << replace;
    EXPECT_TRUE(fs::is_character_file(link)) << "replace = " << replace;
  }
  EXPECT_EQ(Listing(dir_), std::set<std::string>{"null.csv"}) << "a temporary was left behind";
}

TEST_F(OutputFilesTest, AFifoIsWrittenIntoWhenReadAndRefusedWithoutAReader) {
  const fs::path fifo = dir_ / "profile.csv";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(KindOf([&] { AtomicFile file(fifo.string(), true); }), ErrorKind::kCantCreate);
  EXPECT_TRUE(fs::is_fifo(fifo));
  const int reader = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0);
  {
    AtomicFile file(fifo.string(), true);
    file.out() << "abc";
    file.Commit();
  }
  char text[8] = {};
  EXPECT_EQ(::read(reader, text, sizeof text), 3);
  EXPECT_EQ(std::string(text), "abc");
  ::close(reader);
  EXPECT_TRUE(fs::is_fifo(fifo)) << "the FIFO was replaced";
  EXPECT_EQ(Listing(dir_), std::set<std::string>{"profile.csv"});
}

TEST_F(OutputFilesTest, ASocketIsRefusedEvenWithOverwrite) {
  const fs::path path = dir_ / "s.csv";
  const int sock = ::socket(AF_UNIX, SOCK_STREAM, 0);
  ASSERT_GE(sock, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  ASSERT_LT(path.string().size(), sizeof address.sun_path);
  std::snprintf(address.sun_path, sizeof address.sun_path, "%s", path.c_str());
  ASSERT_EQ(::bind(sock, reinterpret_cast<const sockaddr*>(&address), sizeof address), 0);
  EXPECT_EQ(KindOf([&] { AtomicFile file(path.string(), true); }), ErrorKind::kCantCreate);
  EXPECT_TRUE(fs::is_socket(path));
  ::close(sock);
}

TEST_F(OutputFilesTest, AnOutputDirectoryNeverWritesIntoADeviceOrFifo) {
  const fs::path out = dir_ / "export";
  fs::create_directories(out);
  ASSERT_EQ(::mkfifo((out / "particles.csv").c_str(), 0600), 0);
  fs::create_symlink("/dev/null", out / "waves.csv");
  OutputDirectory directory(out.string(), /*overwrite=*/true);
  EXPECT_EQ(KindOf([&] { directory.Add("particles.csv"); }), ErrorKind::kCantCreate);
  EXPECT_EQ(KindOf([&] { directory.Add("waves.csv"); }), ErrorKind::kCantCreate);
  EXPECT_TRUE(fs::is_fifo(out / "particles.csv"));
  EXPECT_TRUE(fs::is_symlink(out / "waves.csv"));
}

}  // namespace
}  // namespace combabc
