/* particlemesh_pcl_c.h is plain C99: compiled with -std=c99 -pedantic -Werror and run. */
#include "particlemesh_pcl/particlemesh_pcl_c.h"

#include <stdio.h>

int main(void) {
  pm_cloud* cloud = NULL;
  pm_pcl_read_info info;
  info.struct_size = (uint32_t)sizeof info;
  if (pm_pcl_abi_version() != PM_PCL_ABI_VERSION) return 1;
  /* A missing file: a status, a message naming it, the output untouched. */
  if (pm_pcl_read_cloud("/nonexistent/particlemesh.pcd", &cloud, &info) != PM_STATUS_IO_ERROR) return 2;
  if (cloud != NULL) return 3;
  if (pm_pcl_last_error_message()[0] == '\0') return 4;
  printf("%s\n", pm_pcl_last_error_message());
  {
    pm_pcl_preprocess_options o;
    pm_pcl_preprocess_options_init(&o);
    if (o.struct_size != sizeof o || o.normal_k != 20 || o.downsampling != PM_PCL_DOWNSAMPLE_NONE) return 5;
    /* No cloud: a status and a message, the output untouched. */
    if (pm_pcl_preprocess(NULL, &o, &cloud, NULL, NULL) != PM_STATUS_INVALID_ARGUMENT || cloud != NULL) return 6;
  }
  return 0;
}
