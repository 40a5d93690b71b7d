# The `slow` label of the GPU tests that take 10 s or more on lavapipe (2 cores), so that `ctest -L gpu -LE slow` is
# a quick pass and `ctest -L slow` the long one (the slow command-line tests are labelled in tests/CMakeLists.txt).
# Read by ctest after the discovered tests are added (tests/CMakeLists.txt appends it to TEST_INCLUDE_FILES); a name
# that is not there (an extra-corpus test without the corpus) is ignored.
set(visbuf_slow_gpu_tests
    AssetBakeRender.EveryAssetBakesToAPackAndRendersLikeItsInMemoryBake
    Classification.ClassifiedShadingEqualsUbershader
    Lights.TiledEqualsAllLights
    MaterialExtensionAssets.ClearCoatTestMatchesTheCpuReference
    MaterialExtensionAssets.UnlitTestMatchesTheCpuReference
    MaterialExtensionsGpu.EveryPathMatchesTheCpuReference
    MaterialExtensionsGpu.SpecularGlossinessRendersLikeItsMetalRoughTwin
    Msaa.VisbufMatchesForwardResolveOnTexturedAsset
    Occlusion.IdImageUnchangedByOcclusionCullingCity
    Occlusion.IdImageUnchangedByOcclusionCullingMsaa
    SceneUpdates.MovingObjectsOcclusionEqualsNoCulling
    Skinning.NormalMappedSkinnedMeshMatchesCpuSkinning
    SwRaster.AnimatedInstancesMatchHardwareRaster)
set_tests_properties(${visbuf_slow_gpu_tests} PROPERTIES LABELS "gpu;slow")
