// Pinocchio timing harness for tools/bench/vs-pinocchio (built against the headers and libraries of the
// `pin` wheel, see the script). Times the same algorithms as tools/bench/pinocchio_timings.py without the
// Python call overhead.
//
// Usage: pinocchio_bench MODEL_NAME MODEL_FILE STATES_FILE [CALLS [ROUNDS]]
//   MODEL_FILE: the Pinocchio model (URDF + free flyer) saved by pinocchio_timings.py with Model.saveToBinary,
//   so the harness needs no URDF parser headers and times exactly the model the Python loops time.
//   STATES_FILE: one state per line, "q(nq) v(nv) a(nv) tau(nv)" in Pinocchio order (pinocchio_timings.py
//   --dump DIR writes both files).
// Protocol (the one of stride's `cargo run --release -p stride-model --example cpu_timings`): the states are
// cycled through in order; one untimed warm-up pass of CALLS/10 calls (default CALLS 20000), then ROUNDS
// rounds (default 7) of CALLS calls; per round, the wall-clock time (std::chrono::steady_clock) and the
// thread's CPU time (clock_gettime(CLOCK_THREAD_CPUTIME_ID), the clock stride reads too) divided by CALLS.
// Output: one line per algorithm, "MODEL_NAME/<algorithm> <wall us per call> <cpu us per call>", each the
// best (smallest) round of its clock.

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/centroidal.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/serialization.hpp>

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct State {
  Eigen::VectorXd q, v, a, tau;
};

std::vector<State> read_states(const std::string &path, long nq, long nv) {
  std::ifstream in(path);
  std::vector<State> states;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    State s{Eigen::VectorXd(nq), Eigen::VectorXd(nv), Eigen::VectorXd(nv), Eigen::VectorXd(nv)};
    for (long i = 0; i < nq; ++i) ls >> s.q[i];
    for (long i = 0; i < nv; ++i) ls >> s.v[i];
    for (long i = 0; i < nv; ++i) ls >> s.a[i];
    for (long i = 0; i < nv; ++i) ls >> s.tau[i];
    if (ls) states.push_back(s);
  }
  return states;
}

double thread_cpu_us() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e6 + static_cast<double>(ts.tv_nsec) * 1e-3;
}

struct Timing {
  double wall_us, cpu_us;
};

template <typename F>
Timing time_us(const std::vector<State> &states, long calls, int rounds, F &&f) {
  const std::size_t n = states.size();
  for (long k = 0; k < calls / 10; ++k) f(states[static_cast<std::size_t>(k) % n]);
  Timing best{1e300, 1e300};
  for (int round = 0; round < rounds; ++round) {
    const double c0 = thread_cpu_us();
    const auto t0 = std::chrono::steady_clock::now();
    for (long k = 0; k < calls; ++k) f(states[static_cast<std::size_t>(k) % n]);
    const auto t1 = std::chrono::steady_clock::now();
    const double c1 = thread_cpu_us();
    const double wall = std::chrono::duration<double, std::micro>(t1 - t0).count() / static_cast<double>(calls);
    best.wall_us = std::min(best.wall_us, wall);
    best.cpu_us = std::min(best.cpu_us, (c1 - c0) / static_cast<double>(calls));
  }
  return best;
}

}  // namespace

int main(int argc, char **argv) {
  if (argc < 4) {
    std::cerr << "usage: pinocchio_bench MODEL_NAME MODEL_FILE STATES_FILE [CALLS [ROUNDS]]\n";
    return 2;
  }
  const std::string name = argv[1];
  const long calls = argc > 4 ? std::atol(argv[4]) : 20000;
  const int rounds = argc > 5 ? std::atoi(argv[5]) : 7;
  if (calls <= 0 || rounds <= 0) {
    std::cerr << "pinocchio_bench: CALLS and ROUNDS must be positive\n";
    return 2;
  }
  pinocchio::Model model;
  model.loadFromBinary(argv[2]);
  pinocchio::Data data(model);
  const auto states = read_states(argv[3], model.nq, model.nv);
  if (states.empty()) {
    std::cerr << "pinocchio_bench: no states in " << argv[3] << "\n";
    return 1;
  }
  double sink = 0.0;
  auto report = [&](const char *algo, Timing t) {
    std::cout << name << "/" << algo << " " << t.wall_us << " " << t.cpu_us << "\n";
  };
  report("set_state", time_us(states, calls, rounds, [&](const State &s) {
           pinocchio::forwardKinematics(model, data, s.q, s.v);
           sink += data.oMi.back().translation()[0];
         }));
  report("fk", time_us(states, calls, rounds, [&](const State &s) {
           pinocchio::framesForwardKinematics(model, data, s.q);
           sink += data.oMf.back().translation()[0];
         }));
  report("jacobians", time_us(states, calls, rounds, [&](const State &s) {
           pinocchio::computeJointJacobians(model, data, s.q);
           sink += data.J(0, 0);
         }));
  report("crba", time_us(states, calls, rounds, [&](const State &s) {
           pinocchio::crba(model, data, s.q);
           sink += data.M(0, 0);
         }));
  report("rnea", time_us(states, calls, rounds, [&](const State &s) {
           pinocchio::rnea(model, data, s.q, s.v, s.a);
           sink += data.tau[0];
         }));
  report("aba", time_us(states, calls, rounds, [&](const State &s) {
           pinocchio::aba(model, data, s.q, s.v, s.tau);
           sink += data.ddq[0];
         }));
  report("cmm", time_us(states, calls, rounds, [&](const State &s) {
           pinocchio::computeCentroidalMap(model, data, s.q);
           sink += data.Ag(0, 0);
         }));
  std::cerr << "pinocchio_bench: " << name << " nq=" << model.nq << " nv=" << model.nv
            << " frames=" << model.nframes << " (checksum " << sink << ")\n";
  return 0;
}
