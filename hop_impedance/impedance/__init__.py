"""impedance"""
