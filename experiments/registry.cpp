// Placeholder until the experiment framework lands.
namespace physgrad_experiments_placeholder { int unused = 0; }
