// Pinocchio timing harness for tools/bench/vs-pinocchio (built against the headers and libraries of the
// `pin` wheel, see the script). Times the same algorithms as tools/bench/pinocchio_timings.py without the
// Python call overhead.
//
// Usage: pinocchio_bench MODEL_NAME MODEL_FILE STATES_FILE [CALLS]
//   MODEL_FILE: the Pinocchio model (URDF + free flyer) saved by pinocchio_timings.py with Model.saveToBinary,
//   so the harness needs no URDF parser headers and times exactly the model the Python loops time.
//   STATES_FILE: one state per line, "q(nq) v(nv) a(nv) tau(nv)" in Pinocchio order (pinocchio_timings.py
//   --dump DIR writes both files).
// Output: one line per algorithm, "MODEL_NAME/<algorithm> <microseconds per call>" (best of 7 rounds).

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

template <typename F>
double time_us(const std::vector<State> &states, long calls, F &&f) {
  double best = 1e300;
  const std::size_t n = states.size();
  for (int round = 0; round < 7; ++round) {
    auto t0 = std::chrono::steady_clock::now();
    for (long k = 0; k < calls; ++k) f(states[static_cast<std::size_t>(k) % n]);
    auto t1 = std::chrono::steady_clock::now();
    double us = std::chrono::duration<double, std::micro>(t1 - t0).count() / static_cast<double>(calls);
    if (us < best) best = us;
  }
  return best;
}

}  // namespace

int main(int argc, char **argv) {
  if (argc < 4) {
    std::cerr << "usage: pinocchio_bench MODEL_NAME MODEL_FILE STATES_FILE [CALLS]\n";
    return 2;
  }
  const std::string name = argv[1];
  const long calls = argc > 4 ? std::atol(argv[4]) : 20000;
  pinocchio::Model model;
  model.loadFromBinary(argv[2]);
  pinocchio::Data data(model);
  const auto states = read_states(argv[3], model.nq, model.nv);
  if (states.empty()) {
    std::cerr << "pinocchio_bench: no states in " << argv[3] << "\n";
    return 1;
  }
  double sink = 0.0;
  auto report = [&](const char *algo, double us) { std::cout << name << "/" << algo << " " << us << "\n"; };
  report("set_state", time_us(states, calls, [&](const State &s) {
           pinocchio::forwardKinematics(model, data, s.q, s.v);
           sink += data.oMi.back().translation()[0];
         }));
  report("fk", time_us(states, calls, [&](const State &s) {
           pinocchio::framesForwardKinematics(model, data, s.q);
           sink += data.oMf.back().translation()[0];
         }));
  report("jacobians", time_us(states, calls, [&](const State &s) {
           pinocchio::computeJointJacobians(model, data, s.q);
           sink += data.J(0, 0);
         }));
  report("crba", time_us(states, calls, [&](const State &s) {
           pinocchio::crba(model, data, s.q);
           sink += data.M(0, 0);
         }));
  report("rnea", time_us(states, calls, [&](const State &s) {
           pinocchio::rnea(model, data, s.q, s.v, s.a);
           sink += data.tau[0];
         }));
  report("aba", time_us(states, calls, [&](const State &s) {
           pinocchio::aba(model, data, s.q, s.v, s.tau);
           sink += data.ddq[0];
         }));
  report("cmm", time_us(states, calls, [&](const State &s) {
           pinocchio::computeCentroidalMap(model, data, s.q);
           sink += data.Ag(0, 0);
         }));
  std::cerr << "pinocchio_bench: " << name << " nq=" << model.nq << " nv=" << model.nv
            << " frames=" << model.nframes << " (checksum " << sink << ")\n";
  return 0;
}
