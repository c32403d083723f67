// The header lines of the CSV series a run writes, each column with its unit in its name
// (`_s`, `_m`, `_N_per_m`: per metre of thickness, `_Ns_per_m`, `_J_per_m`, `_m_per_s`,
// `_rad`; ids, counts and ratios have none). Readers find the columns by these names
// (core/csv.h). DEM and DAN runs write the same forces.csv and front.csv columns (DAN's front
// has two more), so `demlab compare` and `demlab plot` read both alike.
#pragma once

namespace demlab {

inline constexpr const char* kForcesColumns =
    "t_s,fx_slope_N_per_m,fy_slope_N_per_m,fx_arc_N_per_m,fy_arc_N_per_m,fx_barrier_N_per_m,fy_barrier_N_per_m,"
    "fx_total_N_per_m,fy_total_N_per_m,ix_slope_Ns_per_m,iy_slope_Ns_per_m,ix_arc_Ns_per_m,iy_arc_Ns_per_m,"
    "ix_barrier_Ns_per_m,iy_barrier_Ns_per_m,ix_total_Ns_per_m,iy_total_Ns_per_m,fx_gate_N_per_m,fy_gate_N_per_m,"
    "ix_gate_Ns_per_m,iy_gate_Ns_per_m";
inline constexpr const char* kEnergyColumns =
    "t_s,kinetic_translation_J_per_m,kinetic_rotation_J_per_m,potential_J_per_m,elastic_J_per_m,"
    "dissipated_contacts_J_per_m,dissipated_local_J_per_m,dissipated_rotation_J_per_m,work_by_walls_J_per_m,"
    "removed_with_walls_J_per_m,lost_with_discs_J_per_m,balance_J_per_m";
inline constexpr const char* kEnergyBondColumns = ",bond_elastic_J_per_m,bond_break_loss_J_per_m,bonds_intact_fraction";
inline constexpr const char* kFrontColumns = "t_s,s_front_m,displacement_m";
inline constexpr const char* kDanFrontColumns = "t_s,s_front_m,displacement_m,s_tail_m,v_front_m_per_s";
inline constexpr const char* kTrackColumns = "t_s,id,x_m,y_m,vx_m_per_s,vy_m_per_s,angle_rad,omega_rad_per_s";
inline constexpr const char* kDanEnergyColumns =
    "t_s,kinetic_J_per_m,potential_J_per_m,dissipated_friction_J_per_m,other_J_per_m,balance_J_per_m";
// a DAN block's centre: path coordinate, position, speed, thickness normal to the bed (H) and
// earth pressure coefficient (k)
inline constexpr const char* kDanBlockColumns = "t_s,i,s_m,x_m,y_m,v_m_per_s,H_m,k";

}  // namespace demlab
