#include "visbuf/passes/gbuffer_pass.h"

#include "visbuf/shared/bindings_gbuffer.h"
#include "visbuf/shared/types.h"

namespace visbuf::passes {

namespace {

bool canRenderTo(gpu::Device& device, VkFormat format) {
  VkFormatProperties p{};
  vkGetPhysicalDeviceFormatProperties(device.physicalDevice(), format, &p);
  const VkFormatFeatureFlags need = VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT;
  return (p.optimalTilingFeatures & need) == need;
}

}  // namespace

GBufferFormats GBufferFormats::choose(gpu::Device& device, bool clearcoat) {
  GBufferFormats f;
  f.color[0] = VK_FORMAT_R8G8B8A8_SRGB;  // base colour (sRGB-encoded), alpha
  f.color[1] = canRenderTo(device, VK_FORMAT_R16G16_SNORM) ? VK_FORMAT_R16G16_SNORM : VK_FORMAT_R16G16_SFLOAT;
  f.color[2] = VK_FORMAT_R8G8B8A8_UNORM;  // metallic, roughness, occlusion, unlit
  f.color[3] = canRenderTo(device, VK_FORMAT_B10G11R11_UFLOAT_PACK32) ? VK_FORMAT_B10G11R11_UFLOAT_PACK32
                                                                      : VK_FORMAT_R16G16B16A16_SFLOAT;
  // The coat (octahedral normal, roughness, weight); a byte per pixel that nothing reads without coated materials.
  f.color[4] = clearcoat ? VK_FORMAT_R16G16B16A16_SFLOAT : VK_FORMAT_R8_UNORM;
  return f;
}

uint32_t GBufferFormats::bytesPerPixel() const {
  uint32_t n = 0;
  for (VkFormat f : color) n += gpu::formatBytes(f);
  return n;
}

GBufferPass GBufferPass::create(gpu::Device& device, VkDescriptorSetLayout sceneLayout, gpu::Specialization spec,
                                uint32_t listMask) {
  GBufferPass p;
  p.layout = gpu::PassLayout(device, sceneLayout, {{GBUFFER_BINDING_OVERDRAW, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE}},
                             VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT);
  const VkPipelineLayout layout = p.layout.pipelineLayout();
  p.formats = GBufferFormats::choose(device, (spec.materialFeatures & MATERIAL_FEATURE_CLEARCOAT) != 0u);
  for (uint32_t list = 0; list < DRAW_LISTS; ++list) {
    if (!(listMask >> list & 1u)) continue;
    const std::string prefix = drawListMasked(list) ? "gbuffer_masked" : "gbuffer";
    gpu::GraphicsPipelineDesc d = drawListPipelineDesc(spec, list);
    d.vertexShader = "forward.vert";  // the same pulled vertex and interpolated attributes as the forward path
    d.fragmentShader = prefix + ".frag";
    d.colorFormats.assign(p.formats.color.begin(), p.formats.color.end());
    p.pipelines[list][0] = gpu::createGraphicsPipeline(device, layout, d);
    d.fragmentShader = prefix + "_overdraw.frag";
    p.pipelines[list][1] = gpu::createGraphicsPipeline(device, layout, d);
  }
  return p;
}

void GBufferPass::bind(const gpu::Image& overdraw) const {
  layout.writer().image(GBUFFER_BINDING_OVERDRAW, overdraw.view(), VK_IMAGE_LAYOUT_GENERAL).update();
}

void GBufferPass::record(VkCommandBuffer cmd, VkDescriptorSet scene, const GBufferInputs& in) const {
  std::array<VkRenderingAttachmentInfo, GBUFFER_TARGETS> cas{};
  for (uint32_t i = 0; i < GBUFFER_TARGETS; ++i) {
    cas[i].sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO;
    cas[i].imageView = in.targets[i]->view();
    cas[i].imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    cas[i].loadOp = in.clear ? VK_ATTACHMENT_LOAD_OP_CLEAR : VK_ATTACHMENT_LOAD_OP_LOAD;
    cas[i].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    cas[i].clearValue.color = VkClearColorValue{};  // never read where depth stays 0 (background)
  }
  VkRenderingAttachmentInfo da{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  da.imageView = in.depth->view();
  da.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
  da.loadOp = in.clear ? VK_ATTACHMENT_LOAD_OP_CLEAR : VK_ATTACHMENT_LOAD_OP_LOAD;
  da.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  da.clearValue.depthStencil = {0.0f, 0};  // reverse-Z: 0 is infinitely far
  const uint32_t w = in.depth->width(), h = in.depth->height();
  VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
  ri.renderArea = {{0, 0}, {w, h}};
  ri.layerCount = 1;
  ri.colorAttachmentCount = GBUFFER_TARGETS;
  ri.pColorAttachments = cas.data();
  ri.pDepthAttachment = &da;
  vkCmdBeginRendering(cmd, &ri);
  VkViewport vp{0.0f, 0.0f, float(w), float(h), 0.0f, 1.0f};
  VkRect2D sc{{0, 0}, {w, h}};
  vkCmdSetViewport(cmd, 0, 1, &vp);
  vkCmdSetScissor(cmd, 0, 1, &sc);
  layout.bind(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, scene);
  vkCmdBindIndexBuffer(cmd, in.indexBuffer, 0, VK_INDEX_TYPE_UINT32);
  for (const VisibilityList& l : in.lists) {
    if (l.maxDraws == 0) continue;
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelines[l.list][in.countOverdraw ? 1 : 0].handle());
    vkCmdDrawIndexedIndirectCount(cmd, in.draws, VkDeviceSize(l.drawBase) * sizeof(gpu::DrawCommand), in.drawCount,
                                  VkDeviceSize(l.countIndex) * sizeof(uint32_t), l.maxDraws, sizeof(gpu::DrawCommand));
  }
  vkCmdEndRendering(cmd);
}

}  // namespace visbuf::passes
