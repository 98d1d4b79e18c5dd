// OMPL's control-based planners over squeeze's own simulation (issue 19): "ompl:RRT",
// "ompl:KPIECE1", "ompl:SST", "ompl:EST", "ompl:PDST" (Sucan, Moll, Kavraki, "The Open Motion
// Planning Library", IEEE RAM 2012; Debian libompl-dev 1.5). OMPL's headers stay in this file.
//
// The OMPL problem:
//   state space    SqueezeStateSpace: a state holds a whole fem::State (every movable vertex's
//                  position and velocity, of the robot and of every deformable obstacle), with
//                  the robot's and the goal object's centres of mass cached. Its distance is the
//                  distance of the robot's centres of mass (what squeeze's RRT uses for its nearest
//                  node); its sampler puts the robot's rest shape, at rest, at a uniform point of
//                  the bounds (the obstacles as in the start state).
//   control space  SqueezeControlSpace: a control is a squeeze Control (control.h); its sampler
//                  draws the kind by planner.weights, the target (the goal with probability
//                  goal_bias, and always for kinds toward the goal, else uniform in the bounds) and
//                  the kind's own parameters through the kind's sampler, from a squeeze Random
//                  seeded with planner.seed.
//   propagator     a squeeze Propagator (the planning problem's factory): OMPL propagates in
//                  chunks of propagation step size = t_min (rounded to whole time steps), from 1
//                  to round(t_max / t_min) chunks per control; each chunk applies the control
//                  afresh from the state it starts in. A state that breaks a validity check of
//                  the propagator (diverged, volume, bounds, timeout) is invalid.
//   goal           a GoalRegion: the goal object's centre of mass within goal.tolerance.
//   projection     the robot's centre of mass, cells of ¼ its bounding-box diagonal (KPIECE1,
//                  EST, PDST).
// The plan's path is one PathSegment per propagated chunk (same control, the chunk's steps), so a
// replay re-simulates exactly what the planner did and ends in the state whose hash the plan keeps
// (path_states stays empty: only the final state is kept).
//
// Statistics: iterations = controls drawn (each planner draws one or more per expansion); nodes
// = the planner data's vertices. planner.iterations caps the controls drawn; --time-limit stops the
// planner (OMPL's termination condition between iterations, the propagator's deadline within one).
// Determinism: OMPL's random generators are seeded from the seed generator (ompl::RNG::setSeed)
// just before the planner is made, OMPL runs single-threaded here, and squeeze's own draws come
// from its Random: the same seed gives the same plan.
#include <ompl/base/Goal.h>
#include <ompl/base/ProjectionEvaluator.h>
#include <ompl/base/StateSampler.h>
#include <ompl/base/StateSpace.h>
#include <ompl/base/goals/GoalRegion.h>
#include <ompl/control/ControlSampler.h>
#include <ompl/control/ControlSpace.h>
#include <ompl/control/PathControl.h>
#include <ompl/control/PlannerData.h>
#include <ompl/control/SpaceInformation.h>
#include <ompl/control/StatePropagator.h>
#include <ompl/control/planners/est/EST.h>
#include <ompl/control/planners/kpiece/KPIECE1.h>
#include <ompl/control/planners/pdst/PDST.h>
#include <ompl/control/planners/rrt/RRT.h>
#include <ompl/control/planners/sst/SST.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>

#include "squeeze/common/progress.h"
#include "squeeze/plan/planner.h"

namespace squeeze::plan {
namespace {

namespace ob = ompl::base;
namespace oc = ompl::control;

// OMPL's console messages go to spdlog's debug level.
class SpdlogOutput : public ompl::msg::OutputHandler {
 public:
  void log(const std::string& text, ompl::msg::LogLevel, const char* filename, int line) override {
    spdlog::debug("ompl: {} ({}:{})", text, filename, line);
  }
};

struct Shared {
  const PlanningProblem* pb = nullptr;
  const PlannerOptions* options = nullptr;
  Eigen::AlignedBox3d bounds;
};

class SqueezeStateSpace : public ob::StateSpace {
 public:
  struct StateType : ob::State {
    fem::State s;
    Eigen::Vector3d com{0, 0, 0};       // robot's centre of mass (m)
    Eigen::Vector3d goal_com{0, 0, 0};  // goal object's centre of mass (m)
    bool valid = true;                  // false: the propagation that made it broke a validity check
    void assign(const StateType& o) {
      s = o.s;
      com = o.com;
      goal_com = o.goal_com;
      valid = o.valid;
    }
  };
  explicit SqueezeStateSpace(const Shared& sh) : sh_(sh) {
    setName("squeeze");
    dimension_ = static_cast<unsigned>(6 * sh.pb->start.x.rows());
  }
  void update(StateType* st) const {
    st->com = sh_.pb->robot.com(st->s);
    st->goal_com = sh_.pb->goal_object.com(st->s);
  }
  unsigned int getDimension() const override { return dimension_; }
  double getMaximumExtent() const override { return sh_.bounds.diagonal().norm(); }
  double getMeasure() const override { return sh_.bounds.volume(); }
  void enforceBounds(ob::State*) const override {}
  bool satisfiesBounds(const ob::State* s) const override { return sh_.bounds.contains(as(s)->com); }
  void copyState(ob::State* d, const ob::State* s) const override { as(d)->assign(*as(s)); }
  double distance(const ob::State* a, const ob::State* b) const override { return (as(a)->com - as(b)->com).norm(); }
  bool equalStates(const ob::State* a, const ob::State* b) const override {
    return as(a)->s.x == as(b)->s.x && as(a)->s.v == as(b)->s.v;
  }
  void interpolate(const ob::State* from, const ob::State* to, double t, ob::State* out) const override {
    StateType* o = as(out);
    o->assign(*as(from));
    o->s.x = (1 - t) * as(from)->s.x + t * as(to)->s.x;
    o->s.v = (1 - t) * as(from)->s.v + t * as(to)->s.v;
    update(o);
  }
  ob::StateSamplerPtr allocDefaultStateSampler() const override;
  ob::State* allocState() const override {
    auto* st = new StateType;
    st->s = sh_.pb->start;
    update(st);
    return st;
  }
  void freeState(ob::State* s) const override { delete as(s); }
  void registerProjections() override;

  static StateType* as(ob::State* s) { return static_cast<StateType*>(s); }
  static const StateType* as(const ob::State* s) { return static_cast<const StateType*>(s); }
  const Shared& shared() const { return sh_; }

 private:
  const Shared& sh_;
  unsigned dimension_ = 0;
};

// The robot's rest shape at rest, its centre of mass at a point drawn by `where`.
class SqueezeStateSampler : public ob::StateSampler {
 public:
  explicit SqueezeStateSampler(const SqueezeStateSpace* space) : ob::StateSampler(space), sp_(space) {}
  void sampleUniform(ob::State* s) override {
    const Eigen::AlignedBox3d& b = sp_->shared().bounds;
    Eigen::Vector3d p;
    for (int d = 0; d < 3; ++d) p(d) = rng_.uniformReal(b.min()(d), b.max()(d));
    place(s, p);
  }
  void sampleUniformNear(ob::State* s, const ob::State* near, double distance) override {
    Eigen::Vector3d p = SqueezeStateSpace::as(near)->com;
    for (int d = 0; d < 3; ++d) p(d) += rng_.uniformReal(-distance, distance);
    place(s, p);
  }
  void sampleGaussian(ob::State* s, const ob::State* mean, double stdDev) override {
    Eigen::Vector3d p = SqueezeStateSpace::as(mean)->com;
    for (int d = 0; d < 3; ++d) p(d) += rng_.gaussian(0.0, stdDev);
    place(s, p);
  }

 private:
  void place(ob::State* s, const Eigen::Vector3d& p) const {
    auto* st = SqueezeStateSpace::as(s);
    const PlanningProblem& pb = *sp_->shared().pb;
    st->s = pb.start;
    const Robot& r = pb.robot;
    for (int i = 0; i < r.vertices; ++i) {
      if (r.mass(i) <= 0) continue;
      st->s.x.row(r.first_row + i) = (r.rest.row(i).transpose() - r.rest_com + p).transpose();
      st->s.v.row(r.first_row + i).setZero();
    }
    st->valid = true;
    sp_->update(st);
  }
  const SqueezeStateSpace* sp_;
};

ob::StateSamplerPtr SqueezeStateSpace::allocDefaultStateSampler() const {
  return std::make_shared<SqueezeStateSampler>(this);
}

class ComProjection : public ob::ProjectionEvaluator {
 public:
  explicit ComProjection(const SqueezeStateSpace* space) : ob::ProjectionEvaluator(space), sp_(space) {}
  unsigned int getDimension() const override { return 3; }
  void defaultCellSizes() override {
    const PlanningProblem& pb = *sp_->shared().pb;
    const Eigen::Vector3d lo = pb.robot.rest.colwise().minCoeff(), hi = pb.robot.rest.colwise().maxCoeff();
    const double cell = std::max(0.25 * (hi - lo).norm(), 1e-3);
    cellSizes_.assign(3, cell);
  }
  void project(const ob::State* s, Eigen::Ref<Eigen::VectorXd> out) const override {
    out = SqueezeStateSpace::as(s)->com;
  }

 private:
  const SqueezeStateSpace* sp_;
};

void SqueezeStateSpace::registerProjections() {
  registerDefaultProjection(std::make_shared<ComProjection>(this));
}

class SqueezeControlSpace : public oc::ControlSpace {
 public:
  struct ControlType : oc::Control {
    plan::Control c;
  };
  SqueezeControlSpace(const ob::StateSpacePtr& space, const Shared& sh, std::atomic<long long>& drawn)
      : oc::ControlSpace(space), sh_(sh), rng_(sh.options->seed), drawn_(drawn) {
    setName("squeeze_controls");
  }
  unsigned int getDimension() const override { return 10; }  // kind, target (3), force, vertex, radius, omega, param…
  oc::Control* allocControl() const override { return new ControlType; }
  void freeControl(oc::Control* c) const override { delete as(c); }
  void copyControl(oc::Control* d, const oc::Control* s) const override { as(d)->c = as(s)->c; }
  bool equalControls(const oc::Control* a, const oc::Control* b) const override {
    const plan::Control &x = as(a)->c, &y = as(b)->c;
    return x.kind == y.kind && x.target == y.target && x.force == y.force && x.vertex == y.vertex &&
           x.radius == y.radius && x.omega == y.omega && x.param == y.param;
  }
  void nullControl(oc::Control* c) const override {
    as(c)->c = plan::Control();
    as(c)->c.kind = control_kinds().front();
  }
  oc::ControlSamplerPtr allocDefaultControlSampler() const override;

  // The squeeze draw of one control (the RRT's, without the node and the duration).
  void draw(plan::Control& c) const {
    ++drawn_;
    const PlannerOptions& o = *sh_.options;
    c = plan::Control();
    c.kind = o.weights.pick(rng_.uniform());
    if (c.kind->toward_goal() || rng_.uniform() < o.goal_bias) {
      c.target = sh_.pb->goal;
    } else {
      for (int d = 0; d < 3; ++d) c.target(d) = rng_.uniform(sh_.bounds.min()(d), sh_.bounds.max()(d));
    }
    SamplingContext ctx;
    ctx.robot = &sh_.pb->robot;
    ctx.max_force = o.max_force;
    ctx.control_radius = o.control_radius;
    ctx.interpolation_omega = o.interpolation_omega;
    c.kind->sample(c, ctx, rng_);
  }
  static ControlType* as(oc::Control* c) { return static_cast<ControlType*>(c); }
  static const ControlType* as(const oc::Control* c) { return static_cast<const ControlType*>(c); }

 private:
  const Shared& sh_;
  mutable Random rng_;
  std::atomic<long long>& drawn_;
};

class SqueezeControlSampler : public oc::ControlSampler {
 public:
  explicit SqueezeControlSampler(const SqueezeControlSpace* space) : oc::ControlSampler(space), sp_(space) {}
  void sample(oc::Control* c) override { sp_->draw(SqueezeControlSpace::as(c)->c); }

 private:
  const SqueezeControlSpace* sp_;
};

oc::ControlSamplerPtr SqueezeControlSpace::allocDefaultControlSampler() const {
  return std::make_shared<SqueezeControlSampler>(this);
}

struct Counters {
  long long propagations = 0;
  int diverged = 0, volume = 0, bounds = 0;
  bool timed_out = false;
};

class SqueezeStatePropagator : public oc::StatePropagator {
 public:
  SqueezeStatePropagator(const oc::SpaceInformationPtr& si, const SqueezeStateSpace* space, Propagator* p, double h,
                         Counters& n)
      : oc::StatePropagator(si), space_(space), p_(p), h_(h), n_(n) {}
  void propagate(const ob::State* start, const oc::Control* control, double duration,
                 ob::State* result) const override {
    const int steps = std::max(1, static_cast<int>(std::lround(duration / h_)));
    auto* out = SqueezeStateSpace::as(result);
    const Validity v = p_->propagate(SqueezeStateSpace::as(start)->s, SqueezeControlSpace::as(control)->c, steps, out->s);
    ++n_.propagations;
    switch (v) {
      case Validity::valid: break;
      case Validity::diverged: ++n_.diverged; break;
      case Validity::volume: ++n_.volume; break;
      case Validity::bounds: ++n_.bounds; break;
      case Validity::timeout: n_.timed_out = true; break;
    }
    out->valid = v == Validity::valid;
    space_->update(out);
  }
  bool canPropagateBackward() const override { return false; }

 private:
  const SqueezeStateSpace* space_;
  Propagator* p_;
  double h_;
  Counters& n_;
};

class ComGoal : public ob::GoalRegion {
 public:
  ComGoal(const ob::SpaceInformationPtr& si, const Eigen::Vector3d& goal, double tolerance)
      : ob::GoalRegion(si), goal_(goal) {
    setThreshold(tolerance);
  }
  double distanceGoal(const ob::State* s) const override { return (SqueezeStateSpace::as(s)->goal_com - goal_).norm(); }

 private:
  Eigen::Vector3d goal_;
};

using MakeOmplPlanner = std::function<ob::PlannerPtr(const oc::SpaceInformationPtr&)>;

class OmplPlanner : public Planner {
 public:
  OmplPlanner(const char* name, MakeOmplPlanner make) : name_(name), make_(std::move(make)) {}
  const char* name() const override { return name_; }
  PlanResult solve(const PlanningProblem& problem, const PlannerOptions& options, Progress* progress) override;

 private:
  const char* name_;
  MakeOmplPlanner make_;
};

PlanResult OmplPlanner::solve(const PlanningProblem& pb, const PlannerOptions& options, Progress* progress) {
  const auto t0 = std::chrono::steady_clock::now();
  static SpdlogOutput output;
  ompl::msg::useOutputHandler(&output);
  ompl::msg::setLogLevel(ompl::msg::LOG_DEBUG);
  // Every OMPL generator made from here on is seeded from this: the same seed, the same plan.
  ompl::RNG::setSeed(static_cast<std::uint_fast32_t>(options.seed % 4294967291ULL) + 1);

  const fem::SceneWorld& w = *pb.world;
  Shared sh;
  sh.pb = &pb;
  sh.options = &options;
  sh.bounds = w.bounds;
  const double h = w.time_step();
  const int chunk = std::max(1, static_cast<int>(std::lround(options.t_min / h)));
  const int max_chunks = std::max(1, static_cast<int>(std::lround(options.t_max / (chunk * h))));

  std::unique_ptr<Propagator> propagator = pb.make_propagator();
  if (options.time_limit > 0)
    propagator->set_deadline(t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                      std::chrono::duration<double>(options.time_limit)));
  std::atomic<long long> drawn{0};
  Counters counters;

  auto space = std::make_shared<SqueezeStateSpace>(sh);
  auto cspace = std::make_shared<SqueezeControlSpace>(space, sh, drawn);
  auto si = std::make_shared<oc::SpaceInformation>(space, cspace);
  si->setStatePropagator(std::make_shared<SqueezeStatePropagator>(si, space.get(), propagator.get(), h, counters));
  si->setStateValidityChecker([](const ob::State* s) { return SqueezeStateSpace::as(s)->valid; });
  si->setPropagationStepSize(chunk * h);
  si->setMinMaxControlDuration(1, static_cast<unsigned>(max_chunks));
  si->setup();

  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  {
    ob::State* start = space->allocState();
    auto* st = SqueezeStateSpace::as(start);
    st->s = pb.start;
    space->update(st);
    pdef->addStartState(start);
    space->freeState(start);
  }
  pdef->setGoal(std::make_shared<ComGoal>(si, pb.goal, pb.tolerance));

  ob::PlannerPtr planner = make_(si);
  planner->setProblemDefinition(pdef);
  planner->setup();

  if (progress) progress->stage("planning", 0);
  const long long max_draws = options.iterations;
  ob::PlannerTerminationCondition ptc([&] {
    if (drawn.load() >= max_draws) return true;
    if (options.time_limit > 0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >= options.time_limit)
      return true;
    if (progress) progress->update(static_cast<double>(drawn.load()), "controls drawn");
    return false;
  });
  const ob::PlannerStatus status = planner->solve(ptc);
  if (progress) progress->finish();

  PlanResult result;
  result.time_step = h;
  PlanStatistics& st = result.stats;
  const bool exact = status == ob::PlannerStatus::EXACT_SOLUTION;
  const bool approximate = status == ob::PlannerStatus::APPROXIMATE_SOLUTION;
  fem::State last = pb.start;
  if (exact || approximate) {
    const auto* path = pdef->getSolutionPath()->as<oc::PathControl>();
    for (std::size_t i = 0; i < path->getControlCount(); ++i) {
      const int chunks = std::max(1, static_cast<int>(std::lround(path->getControlDuration(i) / (chunk * h))));
      for (int k = 0; k < chunks; ++k) {
        PathSegment seg;
        seg.control = SqueezeControlSpace::as(path->getControl(i))->c;
        seg.steps = chunk;
        result.path.push_back(seg);
      }
    }
    // The planner keeps the state at the end of the path only (path_states stays empty: a replay
    // is checked against its hash); re-simulating every chunk here would cost the time limit.
    if (path->getStateCount() > 0) last = SqueezeStateSpace::as(path->getState(path->getStateCount() - 1))->s;
  }
  const double distance = (pb.goal_object.com(last) - pb.goal).norm();
  result.status = exact && distance <= pb.tolerance ? PlanStatus::solved
                  : result.path.empty()             ? PlanStatus::failed
                                                    : PlanStatus::approximate;
  result.final_state_hash = state_hash(last);
  result.timed_out = counters.timed_out || (options.time_limit > 0 && !exact &&
                                            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >=
                                                options.time_limit);
  ob::PlannerData data(si);
  planner->getPlannerData(data);
  st.iterations = static_cast<int>(drawn.load());
  st.nodes = static_cast<int>(data.numVertices());
  st.discarded_diverged = counters.diverged;
  st.discarded_volume = counters.volume;
  st.discarded_bounds = counters.bounds;
  st.discarded_volume_by_object.assign(static_cast<size_t>(w.world.bodies()), 0);
  st.simulation_steps = propagator->steps_done();
  st.final_distance = distance;
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace

std::unique_ptr<Planner> make_ompl_rrt_planner() {
  return std::make_unique<OmplPlanner>("ompl:RRT", [](const oc::SpaceInformationPtr& si) {
    auto p = std::make_shared<oc::RRT>(si);
    return p;
  });
}
std::unique_ptr<Planner> make_ompl_kpiece1_planner() {
  return std::make_unique<OmplPlanner>("ompl:KPIECE1",
                                       [](const oc::SpaceInformationPtr& si) { return std::make_shared<oc::KPIECE1>(si); });
}
std::unique_ptr<Planner> make_ompl_sst_planner() {
  return std::make_unique<OmplPlanner>("ompl:SST",
                                       [](const oc::SpaceInformationPtr& si) { return std::make_shared<oc::SST>(si); });
}
std::unique_ptr<Planner> make_ompl_est_planner() {
  return std::make_unique<OmplPlanner>("ompl:EST",
                                       [](const oc::SpaceInformationPtr& si) { return std::make_shared<oc::EST>(si); });
}
std::unique_ptr<Planner> make_ompl_pdst_planner() {
  return std::make_unique<OmplPlanner>("ompl:PDST",
                                       [](const oc::SpaceInformationPtr& si) { return std::make_shared<oc::PDST>(si); });
}

}  // namespace squeeze::plan
