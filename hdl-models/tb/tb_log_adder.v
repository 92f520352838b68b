// Self-checking testbench of log_adder: fields per vector: a, b, expected s. The vectors
// stream through the handshake (hs_tb.vh).
`timescale 1ns/1ps
`include "params.vh"
module tb_log_adder;
    `include "hs_tb.vh"
    reg [63:0] e;
    reg [`P_FB-1:0] a, b;
    wire [`P_FB-1:0] s;
    log_adder #(.FB(`P_FB), .TD(`P_TD), .TF(`P_TF), .ADDR_BITS(`P_ADDR_BITS), .SHIFT(`P_SHIFT),
                .INTERP(`P_INTERP), .MAX(`P_MAX), .ROM_FILE("log_rom.hex"))
        dut (.clk(clk), .rst(rst), .in_valid(in_valid), .in_ready(in_ready),
             .out_valid(out_valid), .out_ready(out_ready), .a(a), .b(b), .s(s));
    task drive(input integer k);
        begin
            a = mem[k*`N_FIELDS];
            b = mem[k*`N_FIELDS+1];
        end
    endtask
    task check(input integer k, output reg bad_k);
        begin
            e = mem[k*`N_FIELDS+2];
            bad_k = s !== e[`P_FB-1:0] || e >> `P_FB != 0;
        end
    endtask
    task fail_line;
        $display("TESTBENCH FAILED: %0d of %0d vectors differ, first vector %0d (a=%0h b=%0h expected s=%0h)",
                 errors, total, first, mem[first*`N_FIELDS], mem[first*`N_FIELDS+1], mem[first*`N_FIELDS+2]);
    endtask
endmodule
