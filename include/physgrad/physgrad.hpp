// physgrad — the library in one include: every public header of the core library (the drawing of
// report/, the experiment framework run/, the MPI communicator and the ScaLAPACK eigensolver are
// libraries of their own; the private headers of cmake/private_headers.txt are not installed).
#pragma once

// A test reads this list against include/physgrad/ (tests/front_door_test.cpp).
#include "physgrad/error.hpp"
#include "physgrad/memory.hpp"
#include "physgrad/rule_descriptor.hpp"
#include "physgrad/rule_option.hpp"
#include "physgrad/rule_step.hpp"
#include "physgrad/spectral_cut.hpp"
#include "physgrad/stop.hpp"
#include "physgrad/text.hpp"
#include "physgrad/threads.hpp"
#include "physgrad/types.hpp"

#include "physgrad/io/folder_handle.hpp"

#include "physgrad/physics/checked_simulator.hpp"
#include "physgrad/physics/comparison_toy.hpp"
#include "physgrad/physics/coupled_oscillators.hpp"
#include "physgrad/physics/diagonal_scale.hpp"
#include "physgrad/physics/fpu_chain.hpp"
#include "physgrad/physics/heat_diffusion.hpp"
#include "physgrad/physics/poisson.hpp"
#include "physgrad/physics/poisson_solve.hpp"
#include "physgrad/physics/quantum_dipole.hpp"
#include "physgrad/physics/simulator.hpp"
#include "physgrad/physics/sin_rotation.hpp"

#include "physgrad/loss/fidelity.hpp"
#include "physgrad/loss/loss.hpp"

#include "physgrad/nn/activation.hpp"
#include "physgrad/nn/conv_layers.hpp"
#include "physgrad/nn/conv_net.hpp"
#include "physgrad/nn/dense_layer_gram.hpp"
#include "physgrad/nn/mean_matched_network.hpp"
#include "physgrad/nn/mlp.hpp"
#include "physgrad/nn/network.hpp"

#include "physgrad/parallel/communicator.hpp"
#include "physgrad/parallel/shard.hpp"

#include "physgrad/autodiff/dual.hpp"
#include "physgrad/autodiff/finite_difference.hpp"

#include "physgrad/optim/adam.hpp"
#include "physgrad/optim/bfgs.hpp"
#include "physgrad/optim/domain.hpp"
#include "physgrad/optim/gauss_newton.hpp"
#include "physgrad/optim/gradient_descent.hpp"
#include "physgrad/optim/inverse_gradient.hpp"
#include "physgrad/optim/lbfgs.hpp"
#include "physgrad/optim/levenberg_marquardt.hpp"
#include "physgrad/optim/line_search.hpp"
#include "physgrad/optim/local_inverse.hpp"
#include "physgrad/optim/minimize.hpp"
#include "physgrad/optim/momentum.hpp"
#include "physgrad/optim/newton.hpp"
#include "physgrad/optim/objective.hpp"
#include "physgrad/optim/optimizer.hpp"
#include "physgrad/optim/physical_gradient.hpp"
#include "physgrad/optim/quasi_newton.hpp"

#include "physgrad/inversion/jacobian_operator.hpp"
#include "physgrad/inversion/power_pinv.hpp"
#include "physgrad/inversion/y_step.hpp"

#include "physgrad/learn/adam.hpp"
#include "physgrad/learn/hig.hpp"
#include "physgrad/learn/kronecker_hig.hpp"
#include "physgrad/learn/lanczos_hig.hpp"
#include "physgrad/learn/learning_update.hpp"
#include "physgrad/learn/mapped_jacobian.hpp"
#include "physgrad/learn/schedule.hpp"
#include "physgrad/learn/sgd.hpp"
#include "physgrad/learn/sip.hpp"
#include "physgrad/learn/stacked_jacobian.hpp"
#include "physgrad/learn/switching.hpp"

#include "physgrad/catalogue.hpp"

#include "physgrad/train/dataset.hpp"
#include "physgrad/train/step.hpp"
#include "physgrad/train/trainer.hpp"
