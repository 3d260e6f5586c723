#include "crosscheck/single_process_mpi.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

namespace deli {
namespace {

// The variables these tests read or write, restored when the test ends: the same process may
// run other cross-checks after them.
class MpiEnvironment {
 public:
  MpiEnvironment() {
    for (const std::string& name : names_) {
      const char* value = std::getenv(name.c_str());
      saved_.push_back(value ? std::optional<std::string>(value) : std::nullopt);
      unsetenv(name.c_str());
    }
  }
  ~MpiEnvironment() {
    for (std::size_t i = 0; i < names_.size(); ++i) {
      if (saved_[i]) {
        setenv(names_[i].c_str(), saved_[i]->c_str(), 1);
      } else {
        unsetenv(names_[i].c_str());
      }
    }
  }
  static std::optional<std::string> get(const char* name) {
    const char* value = std::getenv(name);
    return value ? std::optional<std::string>(value) : std::nullopt;
  }

 private:
  const std::vector<std::string> names_{"OMPI_MCA_ess_singleton_isolated",
                                        "OMPI_MCA_btl",
                                        "OMPI_MCA_pml",
                                        "OMPI_COMM_WORLD_SIZE",
                                        "PMIX_RANK",
                                        "PMI_RANK"};
  std::vector<std::optional<std::string>> saved_;
};

// Expected values: Open MPI 4.1's parameters for a singleton that starts no orted daemon
// (ess_singleton_isolated) and loads only the transport to itself (btl self, pml ob1).
TEST(SingleProcessMpi, AsksOpenMpiForAnIsolatedSingletonTalkingOnlyToItself) {
  MpiEnvironment environment;
  prefer_single_process_mpi();
  EXPECT_EQ(MpiEnvironment::get("OMPI_MCA_ess_singleton_isolated"), "1");
  EXPECT_EQ(MpiEnvironment::get("OMPI_MCA_btl"), "self");
  EXPECT_EQ(MpiEnvironment::get("OMPI_MCA_pml"), "ob1");
}

TEST(SingleProcessMpi, KeepsTheUsersOwnSettings) {
  MpiEnvironment environment;
  setenv("OMPI_MCA_btl", "self,vader", 1);
  prefer_single_process_mpi();
  EXPECT_EQ(MpiEnvironment::get("OMPI_MCA_btl"), "self,vader");
  EXPECT_EQ(MpiEnvironment::get("OMPI_MCA_pml"), "ob1");
}

// A rank of a job of several (mpirun -np 2 deli-peers) needs the transports between ranks.
TEST(SingleProcessMpi, LeavesAJobStartedByALauncherAlone) {
  for (const char* launcher_variable : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"}) {
    MpiEnvironment environment;
    setenv(launcher_variable, "2", 1);
    prefer_single_process_mpi();
    EXPECT_EQ(MpiEnvironment::get("OMPI_MCA_ess_singleton_isolated"), std::nullopt)
        << launcher_variable;
    EXPECT_EQ(MpiEnvironment::get("OMPI_MCA_btl"), std::nullopt) << launcher_variable;
    EXPECT_EQ(MpiEnvironment::get("OMPI_MCA_pml"), std::nullopt) << launcher_variable;
  }
}

}  // namespace
}  // namespace deli
