# Included by ctest after the discovered tests are added (see CMakeLists.txt for why).
set_tests_properties(Vda5050MixedFleet.AgentsAndVda5050VehiclesShareTheTasks PROPERTIES DISABLED TRUE)
